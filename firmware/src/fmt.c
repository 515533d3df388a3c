#include "fmt.h"

/* v in decimal, with a point before its last `point` digits (0: none) and
 * at least one digit before the point: the one digit loop behind both
 * fmt_uint and fmt_fixed (a fraction printed on its own would be a second).
 * Loop invariants stay in the loop: hoisted, the divisor 10 takes four
 * call-saved registers and their saves (60 B more on the 328P) to spare four
 * ldi a digit beside a ~600-cycle division. */
__attribute__((optimize("no-move-loop-invariants")))
static uint8_t fmt_digits(char *out, uint32_t v, uint8_t point)
{
    char tmp[FMT_MAX];
    uint8_t n = 0;
    do {
        if (point && n == point)
            tmp[n++] = '.';
        tmp[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v || n <= point);
    for (uint8_t i = 0; i < n; i++)
        out[i] = tmp[n - 1 - i];
    out[n] = 0;
    return n;
}

uint8_t fmt_uint(char *out, uint32_t v) { return fmt_digits(out, v, 0); }

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
    if (decimals > 3)
        decimals = 3;
    float scale = 1.0f; /* 10^decimals: exact in a float */
    for (uint8_t d = decimals; d > 0; d--)
        scale *= 10.0f;
    uint8_t n = 0;
    if (v != v) {  /* NaN never comes from valid input; print something parseable */
        v = 0.0f;
    }
    if (v < 0.0f) {
        v = -v;
        if (v * scale >= 0.5f)
            out[n++] = '-';
    }
    if (v > 4.0e6f)
        v = 4.0e6f;  /* keeps the scaled value inside 32 bits */
    return (uint8_t)(n + fmt_digits(out + n, (uint32_t)(v * scale + 0.5f), decimals));
}
