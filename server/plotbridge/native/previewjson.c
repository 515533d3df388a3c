/* previewjson: the strokes of the preview as JSON
 * (server/plotbridge/importing/preview.py, PreviewBuilder.write).
 *
 * The text is what json.dumps writes for the strokes as lists of [x, y] after numpy's
 * round(s, 3): each value is rint(v * 1000) / 1000 in doubles, and Python writes that
 * double as the shortest text that reads back as it. Below 1e12 that is the decimal
 * rint(v * 1000) / 1000 itself with its trailing zeros dropped (at least one digit
 * after the point): one unit of the third decimal is then more than a unit in the last
 * place, so no shorter decimal reads back as the same double. Larger values are left
 * to the caller.
 */

#include <math.h>
#include <stdint.h>

#include "thousandths.h"

#define MAX_UNITS 1e15   /* thousandths: values below 1e12 */

/* Writes v as described above at o; returns the end, NULL when v is too large. */
static char *value(double v, char *o)
{
    double r = rint(v * 1000.0);
    if (!(fabs(r) < MAX_UNITS))
        return 0;
    return write_thousandths((uint64_t)fabs(r), signbit(r / 1000.0) != 0, 1, o);
}

/* n strokes of sizes[i] points, their x, y interleaved at xy, as
 * [[[x,y],[x,y]],[[x,y]]] at out (room: 2 + n * 3 + points * 44 bytes). Returns the
 * text's length, -1 when a value is too large. */
long strokes_json(long n, const int64_t *sizes, const double *xy, char *out)
{
    char *o = out;
    *o++ = '[';
    for (long s = 0; s < n; s++) {
        if (s)
            *o++ = ',';
        *o++ = '[';
        for (int64_t p = 0; p < sizes[s]; p++) {
            if (p)
                *o++ = ',';
            *o++ = '[';
            if (!(o = value(xy[0], o)))
                return -1;
            *o++ = ',';
            if (!(o = value(xy[1], o)))
                return -1;
            *o++ = ']';
            xy += 2;
        }
        *o++ = ']';
    }
    *o++ = ']';
    return (long)(o - out);
}
