#include "numparse.h"

#define MAX_MAGNITUDE 1.0e9f
#define MAX_SIG_DIGITS 9 /* what a uint32 holds exactly; more cannot change a float */

/* m * 10 + d in shifts and adds (a multiply here is a libgcc call: twice
 * the cycles per digit); while m is below 6553 the result fits 16 bits and
 * is made in 16 (most G-code numbers never leave that: `112.5`, `67.25`),
 * half the cycles of the 32-bit sum */
static inline uint32_t times10_plus(uint32_t m, uint8_t d)
{
    if (m < 6553) {
        uint16_t m2 = (uint16_t)m + (uint16_t)m;
        __asm__("" : "+r"(m2)); /* (or gcc folds it back into the multiply) */
        return (uint16_t)((m2 << 2) + m2 + d);
    }
    uint32_t m2 = m + m;
    __asm__("" : "+r"(m2));
    uint32_t m8 = m2 + m2;
    __asm__("" : "+r"(m8)); /* (and two adds, not a shift loop) */
    return m8 + m8 + m2 + d;
}

uint8_t read_number(const char *line, uint8_t *pos, float *out)
{
    const char *p = line + *pos; /* (a pointer: no index add a character) */
    uint8_t negative = 0;
    if (*p == '-' || *p == '+') {
        negative = *p == '-';
        p++;
    }
    uint32_t mantissa = 0;
    uint8_t sig = 0;       /* significant digits kept in mantissa */
    int16_t exponent = 0;  /* power of ten applied to mantissa */
    uint8_t digits = 0;
    /* one loop for both sides of the point (the digit's sum inlined once:
     * flash); frac is 1 past the point */
    for (uint8_t frac = 0;; p++) {
        uint8_t d = (uint8_t)(*p - '0');
        if (d > 9) {
            if (*p != '.' || frac)
                break;
            frac = 1;
            continue;
        }
        digits++;
        if (sig < MAX_SIG_DIGITS) {
            mantissa = times10_plus(mantissa, d);
            sig += mantissa != 0; /* leading zeros are not significant */
            exponent -= frac;
        } else if (exponent < 100) {
            exponent += 1 - frac; /* a dropped integer digit still scales */
        }
    }
    if (digits == 0)
        return 0;
    *pos = (uint8_t)(p - line);
    if (sig + exponent > 10)  /* more than ten integer digits: surely too big */
        return 0;
    /* powers of ten up to 1e10 are exact in a float, so scale with one
     * multiplication or one division (a division costs ~500 cycles here);
     * the one to three decimals of G-code multiply by a constant instead,
     * within a float's last bit of the division */
    float v = (float)mantissa;
    if (exponent == -1) {
        v *= 0.1f;
    } else if (exponent == -2) {
        v *= 0.01f;
    } else if (exponent == -3) {
        v *= 0.001f;
    } else if (exponent < -40) {
        v = 0.0f;
    } else {
        for (; exponent < -10; exponent += 10)
            v /= 1e10f;
        uint8_t k = (uint8_t)(exponent < 0 ? -exponent : exponent); /* <= 10 */
        float p = 1.0f;
        while (k--)
            p *= 10.0f;
        if (exponent < 0)
            v /= p;
        else
            v *= p;
    }
    if (sig + exponent > 9 && v > MAX_MAGNITUDE) /* (under ten integer digits it cannot be) */
        return 0;
    *out = negative ? -v : v;
    return 1;
}
