/* gcodescan: the G-code importer's fast path (server/plotbridge/importing/gcode.py).
 *
 * Classifies each line of a chunk of text as a common line, G0/G1 X Y [F] [; comment]
 * in any case with spaces and tabs between words, at most max_line characters, a pen
 * line, M3/M4 (PEN_DOWN) or M5 (PEN_UP) alone [; comment], or any other line, and
 * reads the numbers of the common ones. Every other line is read
 * by the importer's general parser, which accepts the common lines too and gives the
 * same result for them (the unit tests compare the two).
 *
 * Numbers are read correctly rounded like Python's float() (number()); the grammar
 * of a number is the general parser's: [-+]? (digits [. digits*] | . digits).
 */

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>

enum { OTHER = 0, RAPID = 1, LINE = 2, PEN_DOWN = 3, PEN_UP = 4 };
#define NUM_MAX 255

static const char *blanks(const char *p, const char *end)
{
    while (p < end && (*p == ' ' || *p == '\t'))
        p++;
    return p;
}

static int digit(const char *p, const char *end)
{
    return p < end && *p >= '0' && *p <= '9';
}

/* Exact powers of ten: every one up to 1e22 is a double. */
static const double POW10[] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10,
                               1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19,
                               1e20, 1e21, 1e22};

/* Reads a number at p; returns the position after it, NULL when there is none. A
 * number of at most 15 digits with at most 22 after the point is its digits (exact in
 * a double) divided by a power of ten (exact too): one correctly rounded division,
 * the value strtod gives. Longer ones go through strtod. */
static const char *number(const char *p, const char *end, double *out)
{
    const char *s = p;
    char buf[NUM_MAX + 1];
    int neg = 0, digits = 0, frac = 0;
    uint64_t m = 0;
    if (p < end && (*p == '-' || *p == '+'))
        neg = *p++ == '-';
    if (digit(p, end)) {
        for (; digit(p, end); p++, digits++)
            m = m * 10 + (uint64_t)(*p - '0');
        if (p < end && *p == '.')
            p++;
        for (; digit(p, end); p++, digits++, frac++)
            m = m * 10 + (uint64_t)(*p - '0');
    } else if (p < end && *p == '.' && digit(p + 1, end)) {
        p++;
        for (; digit(p, end); p++, digits++, frac++)
            m = m * 10 + (uint64_t)(*p - '0');
    } else {
        return NULL;
    }
    if (p - s > NUM_MAX)
        return NULL;
    if (digits <= 15 && frac <= 22) {
        double v = (double)m / POW10[frac];
        *out = neg ? -v : v;
        return p;
    }
    memcpy(buf, s, (size_t)(p - s));
    buf[p - s] = '\0';
    *out = strtod(buf, NULL);
    return p;
}

static const char *letter(const char *p, const char *end, char upper)
{
    p = blanks(p, end);
    return p < end && (*p == upper || *p == upper + 32) ? p + 1 : NULL;
}

/* The end of a line after its last word: p at the end, or at blanks and a `;` comment
 * the general parser reads the same way (no parentheses, no checksum); else NULL. */
static const char *line_end(const char *p, const char *end)
{
    p = blanks(p, end);
    if (p < end && *p == ';') {
        for (p++; p < end; p++)
            if (*p == '(' || *p == ')' || *p == '*')
                return NULL;
    }
    return p == end ? p : NULL;
}

/* A pen line [p, end): M, zeros, 3, 4 or 5 (the general parser's M3, M4, M5). */
static uint8_t pen_line(const char *p, const char *end)
{
    uint8_t kind;
    p = blanks(p, end);
    while (p + 1 < end && *p == '0' && p[1] >= '0' && p[1] <= '9')
        p++;
    if (p >= end || *p < '3' || *p > '5')
        return OTHER;
    kind = *p == '5' ? PEN_UP : PEN_DOWN;
    p++;
    if (p < end && (*p == '.' || (*p >= '0' && *p <= '9')))
        return OTHER;
    return line_end(p, end) ? kind : OTHER;
}

/* One line [p, end) (no newline): its kind, and its numbers when common. */
static uint8_t scan_line(const char *p, const char *end, double *x, double *y, double *f)
{
    uint8_t kind;
    const char *q;
    if ((q = letter(p, end, 'M')))
        return pen_line(q, end);
    if (!(p = letter(p, end, 'G')))
        return OTHER;
    if (p + 1 < end && p[0] == '0' && (p[1] == '0' || p[1] == '1'))
        p++;
    if (p >= end || (*p != '0' && *p != '1'))
        return OTHER;
    kind = *p == '0' ? RAPID : LINE;
    p++;
    if (!(p = letter(p, end, 'X')) || !(p = number(blanks(p, end), end, x)))
        return OTHER;
    if (!(p = letter(p, end, 'Y')) || !(p = number(blanks(p, end), end, y)))
        return OTHER;
    *f = NAN;
    q = letter(p, end, 'F');
    if (q && (!(p = number(blanks(q, end), end, f)) || !(*f > 0)))
        return OTHER;   /* a feed that is not positive: the general parser reports it */
    return line_end(p, end) ? kind : OTHER;
}

/* The lines of text[0, len), which ends with a newline: kind[k] (OTHER, RAPID, LINE,
 * PEN_DOWN or PEN_UP) and for common lines x[k], y[k], f[k] (NaN without F; pen lines:
 * 0, 0, NaN) and feed[k], the last F given at or before line k in its run of
 * consecutive common and pen lines (NaN when none is);
 * start[k]: where line k begins, start[n]: len. Lines holding bytes outside ASCII are
 * OTHER (max_line counts characters); ascii: the caller knows there are none. Returns
 * the number of lines n, at most max_lines. */
long gcode_scan(const char *text, long len, int ascii, long max_lines, long max_line,
                uint8_t *kind, double *x, double *y, double *f, double *feed, long *start)
{
    const char *p = text, *end = text + len;
    long n = 0;
    double run_feed = NAN;
    while (p < end && n < max_lines) {
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        const char *c;
        if (!eol)
            eol = end;
        start[n] = p - text;
        kind[n] = OTHER;
        if (eol - p <= max_line) {
            for (c = ascii ? eol : p; c < eol && (unsigned char)*c < 0x80; c++)
                ;
            if (c == eol)
                kind[n] = scan_line(p, eol, &x[n], &y[n], &f[n]);
        }
        if (kind[n] >= PEN_DOWN) {
            x[n] = y[n] = 0.0;
            f[n] = NAN;
        }
        if (kind[n] == OTHER)
            run_feed = NAN;
        else if (!isnan(f[n]))
            run_feed = f[n];
        feed[n] = run_feed;
        n++;
        p = eol + 1;
    }
    start[n] = len;
    return n;
}
