/* simplify: Ramer-Douglas-Peucker polyline simplification
 * (server/plotbridge/importing/simplify.py), the distance of a point to the segment
 * between the kept points around it. The arithmetic is written out term by term
 * (built with -ffp-contract=off), so a point's distance is the same double in every
 * build; of points at the same greatest distance the first is kept. */

#include <stdint.h>
#include <stdlib.h>

/* Two points at a time in GCC's generic vectors (SSE2 on x86-64, NEON on ARM; the
 * AVX2 build of `farthest` where the CPU has it): the same IEEE operations on each
 * point as one at a time, so the same doubles. The preview's simplification of the
 * import bench's million points: 0.083 -> 0.066 s. */
typedef double vd __attribute__((vector_size(16)));
typedef int64_t vi __attribute__((vector_size(16)));
#define BLEND(mask, yes, no) ((vd)(((vi)(yes) & (mask)) | ((vi)(no) & ~(mask))))

#if defined(__GNUC__) && defined(__x86_64__)
#define CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CLONES
#endif

/* The point strictly between a and b farthest from the segment a-b (the first of
 * equally far ones), its squared distance at *best; -1 when there is none or a
 * distance is NaN. */
CLONES static long farthest(const double *xy, long a, long b, double *best)
{
    double ax = xy[2 * a], ay = xy[2 * a + 1];
    double dx = xy[2 * b] - ax, dy = xy[2 * b + 1] - ay;
    double dd = dx * dx + dy * dy;
    double div = dd > 0 ? dd : 1.0;
    long at = -1, i = a + 1;
    *best = -1.0;
    if (b - i >= 4) {
        const vd vax = {ax, ax}, vay = {ay, ay}, vdx = {dx, dx}, vdy = {dy, dy};
        const vd vdiv = {div, div}, zero = {0.0, 0.0}, one = {1.0, 1.0};
        vd vbest = {-1.0, -1.0};
        vi vat = {-1, -1}, nan = {0, 0}, idx = {i, i + 1};
        const vi two = {2, 2};
        for (; i + 2 <= b; i += 2, idx += two) {
            const double *p = xy + 2 * i;
            vd rx = (vd){p[0], p[2]} - vax, ry = (vd){p[1], p[3]} - vay;
            vd t = (rx * vdx + ry * vdy) / vdiv;
            t = BLEND(t < zero, zero, t);
            t = BLEND(t > one, one, t);
            vd ox = rx - t * vdx, oy = ry - t * vdy;
            vd d2 = ox * ox + oy * oy;
            nan |= d2 != d2;
            vi more = d2 > vbest;
            vbest = BLEND(more, d2, vbest);
            vat = (vat & ~more) | (idx & more);
        }
        if (nan[0] | nan[1])
            return -1;
        /* each lane holds its first farthest point: the farther, or the earlier */
        int k = vbest[1] > vbest[0] || (vbest[1] == vbest[0] && vat[1] < vat[0]);
        *best = vbest[k];
        at = vat[k];
    }
    for (; i < b; i++) {
        double rx = xy[2 * i] - ax, ry = xy[2 * i + 1] - ay;
        double t = (rx * dx + ry * dy) / div;
        t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
        double ox = rx - t * dx, oy = ry - t * dy;
        double d2 = ox * ox + oy * oy;
        if (d2 != d2)
            return -1;
        if (d2 > *best) {
            *best = d2;
            at = i;
        }
    }
    return at;
}

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
        double best;
        long at = farthest(xy, a, b, &best);
        if (at < 0 || !(best > tol2))
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
