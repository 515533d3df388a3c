/* Number formatting without printf (avr-libc's float printf costs ~1.5 kB).
 * Pure. Each writes a NUL-terminated string and returns its length. */
#ifndef FMT_H
#define FMT_H
#include <stdint.h>

#define FMT_MAX 16
uint8_t fmt_uint(char *out, uint32_t v);
uint8_t fmt_int(char *out, int32_t v);
/* fixed point with `decimals` (0..3) digits after the point, rounded half away from zero */
uint8_t fmt_fixed(char *out, float v, uint8_t decimals);
#endif
