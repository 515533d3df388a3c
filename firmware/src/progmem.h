/* Constant tables in flash for the pure modules: avr-libc's PROGMEM on the
 * chip (a table left in RAM costs its size there too), ordinary constants
 * in the host builds. */
#ifndef PROGMEM_H
#define PROGMEM_H
#ifdef __AVR__
#include <avr/pgmspace.h>
#else
#include <stdint.h>
#include <string.h>
#define PROGMEM
#define pgm_read_byte(p) (*(const uint8_t *)(p))
#define pgm_read_word(p) (*(const uint16_t *)(p))
#define memcpy_P memcpy
#endif
#endif
