/* wirebytes: the bytes each program line takes on the wire, for the estimate
 * (server/plotbridge/motion/estimate.py): the compact wire format's rules
 * (server/plotbridge/program/wire.py: Compactor.line, on_step, number, numbered) over
 * the estimate's arrays instead of the text. tests/unit/test_wire_bytes.py holds the
 * two equal line for line.
 *
 * Coordinates are integer thousandths (the program's 3 decimals; float32 keeps them
 * below 8,000 mm); each text's length comes from its digits. The float operations are
 * Python's (step_of; float() of a text is the correctly rounded quotient of its digits
 * by a power of ten), built without FMA contraction, so the steps agree exactly; a tie
 * of the shorter texts' rounding goes as Python formats the double (its exact value
 * against the decimal, from fma's exact product error; an exact tie to even).
 */

#include <math.h>
#include <stdint.h>

#define MAX_LINE_NUMBER 10000000L   /* wire.py's: GRBL's largest N */

/* What the compactor remembers from line to line, in and out. */
typedef struct {
    double spm[2];          /* steps/mm of X and Y ($100, $101) */
    int line_numbers;       /* lines go with an N word */
    int motion;             /* the modal motion (G number), -1: none */
    int64_t feed;           /* the F text in tenths of mm/min, -1: none */
    int64_t orig[2];        /* where the original program is (thousandths) */
    int64_t sent[2];        /* where the wire program is (thousandths) */
    int64_t line;           /* lines counted so far */
} wire_state_t;

static const double POW10[] = {1.0, 10.0, 100.0, 1000.0};

static int digits(int64_t a)
{
    int n = 1;
    while (a >= 10) {
        a /= 10;
        n++;
    }
    return n;
}

/* len(number(m / 1000)): no trailing zeros, no leading zero, "0" for zero. */
static int text_len(int64_t m)
{
    if (m == 0)
        return 1;
    int64_t a = m < 0 ? -m : m;
    int64_t whole = a / 1000, frac = a % 1000;
    int n = (m < 0) + (whole ? digits(whole) : 0);
    if (frac)
        n += frac % 100 == 0 ? 2 : frac % 10 == 0 ? 3 : 4;
    return n;
}

/* wire.py's step_of: the same float operations. */
static double step_of(double v, double spm)
{
    double t = v * spm;
    return t >= 0 ? floor(t + 0.5) : -floor(-t + 0.5);
}

static int64_t floor_div(int64_t a, int64_t b)
{
    int64_t q = a / b;
    return q * b > a ? q - 1 : q;
}

/* on_step(m / 1000): the shortest text of at most 3 decimals on the same step, as its
 * value in thousandths (its length: text_len). */
static int64_t on_step(int64_t m, double spm)
{
    double v = (double)m / 1000.0;
    double target = step_of(v, spm);
    /* which way the double lies from the decimal: decides Python's rounding of a tie */
    double p = v * 1000.0;
    double side = (p - (double)m) + fma(v, 1000.0, -p);
    for (int d = 0; d < 3; d++) {
        int64_t r = d == 0 ? 1000 : d == 1 ? 100 : 10;
        int64_t base = floor_div(m, r), twice = 2 * (m - base * r);
        int64_t q = base + (twice > r || (twice == r && (side > 0 || (side == 0 && (base & 1)))));
        if (step_of((double)q / POW10[d], spm) == target)
            return q * r;
    }
    return m;   /* 3 decimals always land on the step: the value itself */
}

/* Bytes of the next n lines (newline and N word included) into bytes[]. kind: a motion
 * line's G number (0-3), above 3 for a line that is no motion, whose bytes[] (its own,
 * without N word) come in and stay, and whose keeps[] says it leaves the modal state
 * alone; x, y: a motion's end point, i, j: an arc's centre offsets, feed: mm/min. */
void wire_bytes(wire_state_t *s, long n, const uint8_t *kind, const float *x, const float *y,
                const float *i, const float *j, const float *feed, const uint8_t *keeps,
                uint16_t *bytes)
{
    for (long k = 0; k < n; k++) {
        long len;
        int g = kind[k];
        if (g > 3) {
            len = bytes[k];
            if (!keeps[k]) {
                s->motion = -1;
                s->feed = -1;
                s->orig[0] = s->orig[1] = s->sent[0] = s->sent[1] = 0;
            }
        } else {
            int64_t m[2] = {(int64_t)llrint((double)x[k] * 1000.0),
                            (int64_t)llrint((double)y[k] * 1000.0)};
            int64_t w[2] = {on_step(m[0], s->spm[0]), on_step(m[1], s->spm[1])};
            len = 3 + text_len(w[0]) + text_len(w[1]);      /* X, Y and the newline */
            if (g != s->motion)
                len += 2;
            s->motion = g;
            if (g >= 2) {   /* same centre: sent start + I' = original start + I */
                int64_t ci = llrint((double)i[k] * 1000.0) + s->orig[0] - s->sent[0];
                int64_t cj = llrint((double)j[k] * 1000.0) + s->orig[1] - s->sent[1];
                len += 2 + text_len(ci) + text_len(cj);
            }
            if (g >= 1) {
                int64_t f = (int64_t)llrint((double)feed[k] * 10.0);
                if (f != s->feed)
                    len += 1 + text_len(100 * f);
                s->feed = f;
            }
            s->orig[0] = m[0];
            s->orig[1] = m[1];
            s->sent[0] = w[0];
            s->sent[1] = w[1];
        }
        s->line++;
        if (s->line_numbers && s->line <= MAX_LINE_NUMBER)
            len += 1 + digits(s->line);
        bytes[k] = (uint16_t)(len > 65535 ? 65535 : len);
    }
}
