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

/* Digits of a >= 0 (1 for 0); without a loop below a million (a loop's exit is a
 * branch the predictor misses). */
static inline int digits(int64_t a)
{
    int n = 1 + (a >= 10) + (a >= 100) + (a >= 1000) + (a >= 10000) + (a >= 100000);
    for (int64_t p = 1000000; a >= p && n < 19; p *= 10)
        n++;
    return n;
}

/* len(number(m / 1000)): no trailing zeros, no leading zero, "0" for zero. */
static inline int text_len(int64_t m)
{
    int64_t a = m < 0 ? -m : m;
    int64_t whole = a / 1000, frac = a - whole * 1000;
    int point = (frac != 0) * (4 - (frac % 10 == 0) - (frac % 100 == 0));   /* ".d" to ".ddd" */
    return (m < 0) + (whole ? digits(whole) : a == 0) + point;
}

/* wire.py's step_of: the same float operations (floor of a positive double by a cast:
 * without SSE4.1, floor() is a library call). */
static int64_t step_of(double v, double spm)
{
    double t = v * spm;
    return t >= 0 ? (int64_t)(t + 0.5) : -(int64_t)(-t + 0.5);
}

/* The step of m thousandths, step_of(m / 1000.0, spm) (float() of a text of up to 3
 * decimals is that quotient: its digits over a power of ten, correctly rounded), here
 * mostly without the division: m * spm * 0.001 and step_of's product each lie within
 * a few ulps (below 4e-16 of t) of the exact m / 1000 * spm, so both round alike
 * unless this one is within 4e-15 of t of a half, which goes to step_of itself. */
static inline int64_t step_at(int64_t m, double spm)
{
    double t = (double)m * spm * 0.001;
    double a = (t < 0 ? -t : t) + 0.5, margin = a * 4e-15;
    int64_t n = (int64_t)a;
    double above = a - (double)n;
    if (__builtin_expect(above < margin || above > 1 - margin, 0))
        return step_of((double)m / 1000.0, spm);
    return t < 0 ? -n : n;
}

/* m thousandths rounded to a multiple of r (1000, 100 or 10: a text of 0 to 2
 * decimals) as Python formats the double m / 1000 (`side`: its sign against the
 * decimal decides a tie; an exact tie goes to even), in thousandths. */
static inline int64_t rounded(int64_t m, int64_t r, double side)
{
    int64_t base = m / r;
    base -= base * r > m;       /* floor */
    int64_t twice = 2 * (m - base * r);
    int64_t up = (twice > r) | ((twice == r) & ((side > 0) | ((side == 0) & (base & 1))));
    return (base + up) * r;
}

/* on_step(m / 1000): the shortest text of at most 3 decimals on the same step, as its
 * value in thousandths (its length: text_len). All three shorter texts are tried and
 * the shortest that lands is taken without a branch (which one lands is a coin toss
 * to the branch predictor). */
static int64_t on_step(int64_t m, double spm)
{
    int64_t target = step_at(m, spm);
    /* which way the double lies from the decimal: decides Python's rounding of a tie
     * (only a tie needs it: fma may be a slow library call) */
    double side = 0.0;
    int64_t a = m < 0 ? -m : m;
    if (a % 10 == 5 || a % 100 == 50 || a % 1000 == 500) {
        double v = (double)m / 1000.0, p = v * 1000.0;
        side = (p - (double)m) + fma(v, 1000.0, -p);
    }
    int64_t q0 = rounded(m, 1000, side), q1 = rounded(m, 100, side), q2 = rounded(m, 10, side);
    int64_t out = m;    /* 3 decimals always land on the step: the value itself */
    out = step_at(q2, spm) == target ? q2 : out;
    out = step_at(q1, spm) == target ? q1 : out;
    out = step_at(q0, spm) == target ? q0 : out;
    return out;
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
            int64_t m[2] = {llrint((double)x[k] * 1000.0), llrint((double)y[k] * 1000.0)};
            int64_t w[2] = {on_step(m[0], s->spm[0]), on_step(m[1], s->spm[1])};
            len = 3 + text_len(w[0]) + text_len(w[1]);      /* X, Y and the newline */
            len += 2 * (g != s->motion);
            s->motion = g;
            if (g >= 2) {   /* same centre: sent start + I' = original start + I */
                int64_t ci = llrint((double)i[k] * 1000.0) + s->orig[0] - s->sent[0];
                int64_t cj = llrint((double)j[k] * 1000.0) + s->orig[1] - s->sent[1];
                len += 2 + text_len(ci) + text_len(cj);
            }
            if (g >= 1) {
                int64_t f = llrint((double)feed[k] * 10.0);
                len += (f != s->feed) * (1 + text_len(100 * f));
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
