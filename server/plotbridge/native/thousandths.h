/* Writing a count of thousandths as a decimal: the number formats of movelines.c and
 * previewjson.c. */
#ifndef THOUSANDTHS_H
#define THOUSANDTHS_H

#include <stdint.h>

/* m thousandths at o: a '-' when neg, the whole part, '.', then three digits, or when
 * trim only up to the last one that is not 0 (at least one). Returns the end. */
static inline char *write_thousandths(uint64_t m, int neg, int trim, char *o)
{
    char digits[24];
    int k = 0;
    uint64_t whole = m / 1000;
    unsigned frac = (unsigned)(m % 1000);
    if (neg)
        *o++ = '-';
    do {
        digits[k++] = (char)('0' + whole % 10);
        whole /= 10;
    } while (whole);
    while (k)
        *o++ = digits[--k];
    *o++ = '.';
    *o++ = (char)('0' + frac / 100);
    if (!trim || frac % 100) {
        *o++ = (char)('0' + frac / 10 % 10);
        if (!trim || frac % 10)
            *o++ = (char)('0' + frac % 10);
    }
    return o;
}

#endif
