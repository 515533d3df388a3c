/* Index arithmetic for single-producer/single-consumer byte rings. Head and
 * tail run freely over 0..255 and are masked on access, so a ring of SIZE
 * (a power of two, at most 128) holds all SIZE bytes: the receive ring really
 * offers the 128 bytes a character-counting sender assumes.
 * Pure: used by the UART rings and tested on the host. */
#ifndef RING_H
#define RING_H
#include <stdint.h>

static inline uint8_t ring_count(uint8_t head, uint8_t tail) { return (uint8_t)(head - tail); }
static inline uint8_t ring_free(uint8_t head, uint8_t tail, uint8_t size)
{
    return (uint8_t)(size - ring_count(head, tail));
}
static inline uint8_t ring_slot(uint8_t index, uint8_t size) { return (uint8_t)(index & (size - 1u)); }
#endif
