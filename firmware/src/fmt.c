#include "fmt.h"

uint8_t fmt_uint(char *out, uint32_t v)
{
    char tmp[10];
    uint8_t n = 0;
    do {
        tmp[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v);
    for (uint8_t i = 0; i < n; i++)
        out[i] = tmp[n - 1 - i];
    out[n] = 0;
    return n;
}

uint8_t fmt_int(char *out, int32_t v)
{
    if (v < 0) {
        out[0] = '-';
        return (uint8_t)(1 + fmt_uint(out + 1, (uint32_t)(-(v + 1)) + 1u));
    }
    return fmt_uint(out, (uint32_t)v);
}

uint8_t fmt_fixed(char *out, float v, uint8_t decimals)
{
    static const uint16_t scale[] = {1, 10, 100, 1000};
    if (decimals > 3)
        decimals = 3;
    uint8_t n = 0;
    if (v != v) {  /* NaN never comes from valid input; print something parseable */
        v = 0.0f;
    }
    if (v < 0.0f) {
        v = -v;
        if (v * scale[decimals] >= 0.5f)
            out[n++] = '-';
    }
    if (v > 4.0e6f)
        v = 4.0e6f;  /* keeps the scaled value inside 32 bits */
    uint32_t whole = (uint32_t)(v * scale[decimals] + 0.5f);
    n = (uint8_t)(n + fmt_uint(out + n, whole / scale[decimals]));
    if (decimals) {
        out[n++] = '.';
        uint32_t frac = whole % scale[decimals];
        for (uint8_t d = decimals; d > 0; d--) {
            out[n + d - 1] = (char)('0' + frac % 10u);
            frac /= 10u;
        }
        n = (uint8_t)(n + decimals);
        out[n] = 0;
    }
    return n;
}
