/* movelines: the normalized program's G0/G1 lines for a run of moves
 * (server/plotbridge/importing/program.py, ProgramWriter.moves).
 *
 * Each point is rounded to the program's 0.001 mm as Python's f"{v:.3f}" rounds it
 * (the exact binary value, ties to even), the rounded value is the one float() reads
 * back from that text, points equal to the one before are dropped, and each kept point
 * is written as `G0 X<x> Y<y>` (rapid) or `G1 X<x> Y<y> F<feed text>`. The feed texts
 * come from the caller (one per distinct feed), so every number format has one source.
 * A run with a point outside the work area (or too large to write) is left to the
 * caller's point-by-point path, which reports or clamps it.
 */

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "thousandths.h"

#define MAX_ABS 1e12   /* beyond this, v * 1000 is not exact to a quarter unit */

/* v rounded to 3 decimals as text at out; *back: the float the text reads as.
 * Returns the text's length. |v| <= MAX_ABS. */
static int fixed3(double v, char *out, double *back)
{
    double p = v * 1000.0;
    double whole = (double)(int64_t)p;  /* floor(p), without a call into libm */
    if (whole > p)
        whole -= 1.0;
    double frac = p - whole;    /* exact: |p| < 2^50, so ulp(p) <= 1/8 */
    int64_t n = (int64_t)whole;
    /* p is v * 1000 rounded; only an exact half of p needs the product's rounding
     * error to decide which way the exact value lies (any other frac is at least one
     * ulp(p) away from the half, more than the error). */
    if (frac > 0.5)
        n++;
    else if (frac == 0.5) {
        double err = fma(v, 1000.0, -p);
        if (err > 0 || (err == 0 && (n & 1)))
            n++;
    }
    int neg = signbit(v) != 0;
    *back = neg && n == 0 ? -0.0 : (double)n / 1000.0;
    char *o = write_thousandths(neg ? (uint64_t)(-n) : (uint64_t)n, neg, 0, out);
    return (int)(o - out);
}

/* Where feed f is in feed_val (n_feeds values, sorted), or where it would go. */
static long feed_index(double f, const double *feed_val, long n_feeds)
{
    long lo = 0, hi = n_feeds;
    while (lo < hi) {
        long mid = (lo + hi) / 2;
        if (feed_val[mid] < f)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* A writer's buffers (room for as many moves as a run has) and results. */
typedef struct {
    const double *x, *y, *feed; /* the run: points and feeds (NaN: a rapid) */
    double area[4];             /* min x, min y, max x, max y: the work area */
    uint8_t kind_rapid, kind_line; /* the estimate's codes for G0 and G1 */
    char *text;                 /* the lines, each ending with a newline */
    double *xy;                 /* kept points, rounded, x and y interleaved */
    double length;              /* in: a running total; out: plus the run's length,
                                 * summed move by move as ProgramWriter.move sums */
    uint8_t *kind;              /* the estimate's inputs: kind_rapid or kind_line, */
    float *x32, *y32, *f32;     /* the point and the feed (0 for a rapid) as floats, */
    uint16_t *nbytes;           /* and the line's length with its newline */
    long text_len;
    double bounds[4];           /* min x, min y, max x, max y of the kept points */
    /* The feed texts: feed_val[i] (n_feeds values, sorted) is written as
     * feed_text[feed_off[i] .. feed_off[i + 1]). */
    const double *feed_val;
    long n_feeds;
    const char *feed_text;
    const int64_t *feed_off;
    double *unknown;            /* feeds of a run missing from the texts */
    long n_unknown;
} movelines_t;

/* Gathers the feeds of a run that have no text yet; returns how many (repeats
 * included). */
static long unknown_feeds(movelines_t *m, long n, const double *feed)
{
    double last = NAN;
    m->n_unknown = 0;
    for (long k = 0; k < n; k++) {
        double f = feed[k];
        if (isnan(f) || f == last)
            continue;
        last = f;
        long i = feed_index(f, m->feed_val, m->n_feeds);
        if (i == m->n_feeds || m->feed_val[i] != f)
            m->unknown[m->n_unknown++] = f;
    }
    return m->n_unknown;
}

/* Writes the lines of n moves of m's run (to x[k], y[k] at feed[k]) from (x0, y0) into
 * m's buffers (text: room for n lines of 48 + the longest feed text bytes).
 * Returns the number of moves kept; -1 when a rounded point is outside the area, -2
 * when feeds have no text (m->unknown); nothing usable is written then. Bounds: min
 * and max as Python's min() and max() give them (the first of equal values, which
 * tells 0.0 from -0.0). */
long moves_lines(movelines_t *m, long n, double x0, double y0)
{
    const double *x = m->x, *y = m->y, *feed = m->feed;
    char *o = m->text;
    long kept = 0, fi = 0;
    double px = x0, py = y0, last_feed = NAN;
    const double *area = m->area;
    const char *feed_text = m->feed_text;
    const int64_t *feed_off = m->feed_off;
    if (unknown_feeds(m, n, feed))
        return -2;
    for (long k = 0; k < n; k++) {
        char xt[32], yt[32];
        double rx, ry;
        if (!(fabs(x[k]) <= MAX_ABS && fabs(y[k]) <= MAX_ABS))
            return -1;
        int xl = fixed3(x[k], xt, &rx), yl = fixed3(y[k], yt, &ry);
        if (!(area[0] <= rx && rx <= area[2] && area[1] <= ry && ry <= area[3]))
            return -1;
        if (rx == px && ry == py)
            continue;
        char *start = o;
        int rapid = isnan(feed[k]);
        memcpy(o, rapid ? "G0 X" : "G1 X", 4);
        o += 4;
        memcpy(o, xt, (size_t)xl);
        o += xl;
        memcpy(o, " Y", 2);
        o += 2;
        memcpy(o, yt, (size_t)yl);
        o += yl;
        if (!rapid) {
            if (feed[k] != last_feed) {
                last_feed = feed[k];
                fi = feed_index(last_feed, m->feed_val, m->n_feeds);
            }
            memcpy(o, " F", 2);
            o += 2;
            memcpy(o, feed_text + feed_off[fi], (size_t)(feed_off[fi + 1] - feed_off[fi]));
            o += feed_off[fi + 1] - feed_off[fi];
        }
        *o++ = '\n';
        m->xy[2 * kept] = rx;
        m->xy[2 * kept + 1] = ry;
        double dx = rx - px, dy = ry - py;
        m->length += sqrt(dx * dx + dy * dy);
        m->kind[kept] = rapid ? m->kind_rapid : m->kind_line;
        m->x32[kept] = (float)rx;
        m->y32[kept] = (float)ry;
        m->f32[kept] = rapid ? 0.0f : (float)feed[k];
        m->nbytes[kept] = (uint16_t)(o - start);
        if (!kept) {
            m->bounds[0] = m->bounds[2] = rx;
            m->bounds[1] = m->bounds[3] = ry;
        } else {
            if (rx < m->bounds[0])
                m->bounds[0] = rx;
            if (ry < m->bounds[1])
                m->bounds[1] = ry;
            if (rx > m->bounds[2])
                m->bounds[2] = rx;
            if (ry > m->bounds[3])
                m->bounds[3] = ry;
        }
        px = rx;
        py = ry;
        kept++;
    }
    m->text_len = (long)(o - m->text);
    return kept;
}
