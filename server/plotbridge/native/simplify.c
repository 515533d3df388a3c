/* simplify: Ramer-Douglas-Peucker polyline simplification
 * (server/plotbridge/importing/simplify.py), the distance of a point to the segment
 * between the kept points around it. The arithmetic is written out term by term
 * (built with -ffp-contract=off), so a point's distance is the same double in every
 * build; of points at the same greatest distance the first is kept. */

#include <stdint.h>
#include <stdlib.h>

/* n points, x and y interleaved at xy.
 * keep[k] (0/1) on entry: points always kept, which include the first and the last.
 * On return: every point to keep for a simplification within sqrt(tol2). Returns 0,
 * or -1 when out of memory (keep is then unchanged). */
int simplify_mask(long n, const double *xy, double tol2, uint8_t *keep)
{
    long *stack = malloc(sizeof(long) * 2 * (size_t)(n > 0 ? n : 1));
    long top = 0, prev = -1;
    if (!stack)
        return -1;
    for (long k = 0; k < n; k++) {
        if (!keep[k])
            continue;
        if (prev >= 0 && k > prev + 1) {
            stack[top++] = prev;
            stack[top++] = k;
        }
        prev = k;
    }
    while (top) {
        long b = stack[--top], a = stack[--top];
        double ax = xy[2 * a], ay = xy[2 * a + 1];
        double dx = xy[2 * b] - ax, dy = xy[2 * b + 1] - ay;
        double dd = dx * dx + dy * dy;
        double div = dd > 0 ? dd : 1.0;
        double best = -1.0;
        long at = -1;
        int nan = 0;
        for (long i = a + 1; i < b; i++) {
            double rx = xy[2 * i] - ax, ry = xy[2 * i + 1] - ay;
            double t = (rx * dx + ry * dy) / div;
            t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
            double ox = rx - t * dx, oy = ry - t * dy;
            double d2 = ox * ox + oy * oy;
            if (d2 != d2)
                nan = 1;
            else if (d2 > best) {
                best = d2;
                at = i;
            }
        }
        if (nan || !(best > tol2))
            continue;
        keep[at] = 1;
        if (at > a + 1) {
            stack[top++] = a;
            stack[top++] = at;
        }
        if (b > at + 1) {
            stack[top++] = at;
            stack[top++] = b;
        }
    }
    free(stack);
    return 0;
}
