/* A float's IEEE bits: integer tests in place of the float library's
 * compares (~50-80 cycles each on the AVR with the call), one source for
 * the main loop's files. */
#ifndef FLOAT_BITS_H
#define FLOAT_BITS_H
#include <stdint.h>
#include <string.h>

static inline uint32_t float_bits(float v)
{
    uint32_t b;
    memcpy(&b, &v, sizeof(b));
    return b;
}

/* the same value, bit for bit (a NaN equal to itself, -0 not +0) */
static inline uint8_t float_same(float a, float b) { return float_bits(a) == float_bits(b); }

#endif
