/* movelines: the normalized program's lines for a run of moves and pen changes
 * (server/plotbridge/importing/program.py, ProgramWriter.moves and .path).
 *
 * Each point is rounded to the program's 0.001 mm as Python's f"{v:.3f}" rounds it
 * (the exact binary value, ties to even), the rounded value is the one float() reads
 * back from that text, points equal to the one before are dropped, and each kept point
 * is written as `G0 X<x> Y<y>` (rapid) or `G1 X<x> Y<y> F<feed text>`. The feed texts
 * come from the caller (one per distinct feed), so every number format has one source.
 * A pen change is `M3` or `M5` (one that changes nothing is not written), as
 * ProgramWriter.pen writes it. Alongside the text: the estimate's rows, the kept points,
 * the preview's calls and the writer's running totals. The run stops at a point outside
 * the work area (or too large to write) and at a pen down the writer must see to itself
 * (its first layer, travel outside the area waiting); the caller takes that one element
 * its own way, which reports or clamps it, and goes on from the next.
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

/* The kinds of a run's elements (gcodescan.c's): NONE does nothing. */
enum { NONE = 0, RAPID = 1, LINE = 2, PEN_DOWN = 3, PEN_UP = 4 };
/* The preview's calls (PreviewBuilder): pen_down(a), pen_up(a) with a program line;
 * draw_path / move through the kept points [a, b) from the point before a (the run's
 * start before the first). */
enum { EV_DOWN = 0, EV_UP = 1, EV_DRAW = 2, EV_TRAVEL = 3 };

/* A writer's buffers (room for as many elements as a run has), state and results. */
typedef struct {
    const double *x, *y, *feed; /* the run: points and feeds (NaN: a rapid) */
    const uint8_t *op;          /* the kind of each element; NULL: all moves */
    double area[4];             /* min x, min y, max x, max y: the work area */
    uint8_t kind_rapid, kind_line, kind_dwell; /* the estimate's codes */
    int pen_ok;                 /* in: a pen down may be written here */
    double settle;              /* seconds a pen change waits (the estimate's dwell) */
    /* The writer's state, in and out: position, pen, program lines written, pen
     * lifts, lengths summed move by move as ProgramWriter.move sums, bounds of the
     * drawing (min x, min y, max x, max y: as Python's min() and max() give them, the
     * first of equal values, which tells 0.0 from -0.0). */
    double px, py;
    int down;
    long line, lifts;
    double down_mm, travel_mm;
    double bounds[4];
    /* Out: the lines, each ending with a newline; */
    char *text;
    long text_len;
    /* the estimate's rows, one a line: kind, point and feed (0 for a rapid; a pen
     * change: kind_dwell, settle, 0, 0) as floats, the line's length with its newline; */
    uint8_t *kind;
    float *x32, *y32, *f32;
    uint16_t *nbytes;
    long rows;
    double *xy;                 /* kept points, rounded, x and y interleaved */
    long n_xy;
    uint8_t *ev;                /* the preview's calls */
    int64_t *ev_a, *ev_b;
    long n_ev;
    /* The feed texts: feed_val[i] (n_feeds values, sorted) is written as
     * feed_text[feed_off[i] .. feed_off[i + 1]). */
    const double *feed_val;
    long n_feeds;
    const char *feed_text;
    const int64_t *feed_off;
    double *unknown;            /* feeds of a run missing from the texts */
    long n_unknown;
} movelines_t;

/* The kind of element k of a run (op: the kinds, or NULL when all are moves). */
static int kind_of(const uint8_t *op, const double *feed, long k)
{
    return op ? op[k] : isnan(feed[k]) ? RAPID : LINE;
}

/* Gathers the feeds of a run's n elements that have no text yet; returns how many
 * (repeats included). */
static long unknown_feeds(movelines_t *m, long n)
{
    double last = NAN;
    m->n_unknown = 0;
    for (long k = 0; k < n; k++) {
        double f = m->feed[k];
        if (kind_of(m->op, m->feed, k) != LINE || f == last)
            continue;
        last = f;
        long i = feed_index(f, m->feed_val, m->n_feeds);
        if (i == m->n_feeds || m->feed_val[i] != f)
            m->unknown[m->n_unknown++] = f;
    }
    return m->n_unknown;
}

static void grow(double *b, double x, double y)
{
    if (x < b[0])
        b[0] = x;
    if (y < b[1])
        b[1] = y;
    if (x > b[2])
        b[2] = x;
    if (y > b[3])
        b[3] = y;
}

/* Writes elements [from, n) of m's run (moves to x[k], y[k] at feed[k]; pen changes)
 * from m's state into m's buffers (text: room for n lines of 48 + the longest feed
 * text bytes; the others: n each). Returns the element it stopped at (n when done:
 * the caller writes that one itself, then goes on from the next), or -2 when feeds
 * have no text (m->unknown; nothing is written then). The run's feeds are checked
 * on its first call, from 0, which comes first (once per run, not once per stop: a
 * run far outside the area stops at every point). */
long moves_lines(movelines_t *m, long from, long n)
{
    /* The state and the counts are kept in locals, written back at the end: the text
     * is written through a char pointer, which may alias anything in *m. */
    const double *x = m->x, *y = m->y, *feed = m->feed;
    char *o = m->text;
    long k, fi = 0, rows = 0, n_xy = 0, n_ev = 0, line = m->line, lifts = m->lifts;
    double px = m->px, py = m->py, last_feed = NAN;
    double down_mm = m->down_mm, travel_mm = m->travel_mm;
    double b[4] = {m->bounds[0], m->bounds[1], m->bounds[2], m->bounds[3]};
    int pen = m->down;
    const double area[4] = {m->area[0], m->area[1], m->area[2], m->area[3]};
    const char *feed_text = m->feed_text;
    const int64_t *feed_off = m->feed_off;
    const double *feed_val = m->feed_val;
    const long n_feeds = m->n_feeds;
    const uint8_t *op = m->op;
    uint8_t *kind_out = m->kind, *ev = m->ev;
    float *x32 = m->x32, *y32 = m->y32, *f32 = m->f32;
    uint16_t *nbytes = m->nbytes;
    double *xy = m->xy;
    int64_t *ev_a = m->ev_a, *ev_b = m->ev_b;
    const uint8_t kind_rapid = m->kind_rapid, kind_line = m->kind_line;
    const uint8_t kind_dwell = m->kind_dwell;
    const float settle = (float)m->settle;
    const int pen_ok = m->pen_ok;
    if (!from && unknown_feeds(m, n))
        return -2;
    for (k = from; k < n; k++) {
        char xt[32], yt[32];
        double rx, ry;
        int kind = kind_of(op, feed, k);
        if (kind == NONE)
            continue;
        if (kind == PEN_DOWN || kind == PEN_UP) {
            int down = kind == PEN_DOWN;
            if (down == pen)
                continue;
            if (down && !pen_ok)
                break;
            pen = down;
            memcpy(o, down ? "M3\n" : "M5\n", 3);
            o += 3;
            line++;
            kind_out[rows] = kind_dwell;
            x32[rows] = settle;
            y32[rows] = f32[rows] = 0.0f;
            nbytes[rows++] = 3;
            ev[n_ev] = down ? EV_DOWN : EV_UP;
            ev_a[n_ev] = line;
            ev_b[n_ev++] = line + 1;
            if (down)
                grow(b, px, py);
            else
                lifts++;
            continue;
        }
        if (!(fabs(x[k]) <= MAX_ABS && fabs(y[k]) <= MAX_ABS))
            break;
        int xl = fixed3(x[k], xt, &rx), yl = fixed3(y[k], yt, &ry);
        if (!(area[0] <= rx && rx <= area[2] && area[1] <= ry && ry <= area[3]))
            break;
        if (rx == px && ry == py)
            continue;
        char *start = o;
        int rapid = kind == RAPID;
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
                fi = feed_index(last_feed, feed_val, n_feeds);
            }
            memcpy(o, " F", 2);
            o += 2;
            memcpy(o, feed_text + feed_off[fi], (size_t)(feed_off[fi + 1] - feed_off[fi]));
            o += feed_off[fi + 1] - feed_off[fi];
        }
        *o++ = '\n';
        line++;
        kind_out[rows] = rapid ? kind_rapid : kind_line;
        x32[rows] = (float)rx;
        y32[rows] = (float)ry;
        f32[rows] = rapid ? 0.0f : (float)feed[k];
        nbytes[rows++] = (uint16_t)(o - start);
        double dx = rx - px, dy = ry - py;
        double d = sqrt(dx * dx + dy * dy);
        /* the preview's draw or travel: it extends the one before when that is the
         * same and ends here */
        uint8_t e = pen ? EV_DRAW : EV_TRAVEL;
        if (n_ev && ev[n_ev - 1] == e && ev_b[n_ev - 1] == n_xy) {
            ev_b[n_ev - 1] = n_xy + 1;
        } else {
            ev[n_ev] = e;
            ev_a[n_ev] = n_xy;
            ev_b[n_ev++] = n_xy + 1;
        }
        if (pen) {
            down_mm += d;
            grow(b, rx, ry);
        } else {
            travel_mm += d;
        }
        xy[2 * n_xy] = rx;
        xy[2 * n_xy + 1] = ry;
        n_xy++;
        px = rx;
        py = ry;
    }
    m->px = px;
    m->py = py;
    m->down = pen;
    m->line = line;
    m->lifts = lifts;
    m->down_mm = down_mm;
    m->travel_mm = travel_mm;
    memcpy(m->bounds, b, sizeof b);
    m->rows = rows;
    m->n_xy = n_xy;
    m->n_ev = n_ev;
    m->text_len = (long)(o - m->text);
    return k;
}
