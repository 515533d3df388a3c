#include <math.h>
#include "arc.h"
#include "status.h"

#define FULL_CIRCLE_EPS 5.0e-7f

uint8_t arc_init(arc_t *arc, const float *start, const float *target, const float *center,
                 uint8_t clockwise, float tolerance)
{
    float sx = start[0] - center[0], sy = start[1] - center[1];
    float ex = target[0] - center[0], ey = target[1] - center[1];
    arc->r0 = sqrtf(sx * sx + sy * sy);
    arc->r1 = sqrtf(ex * ex + ey * ey);
    if (arc->r0 <= 0.0f || arc->r1 <= 0.0f || tolerance <= 0.0f)
        return ERR_INVALID_TARGET;
    float sweep = atan2f(sx * ey - sy * ex, sx * ex + sy * ey);
    /* the same start and end point means a full turn */
    if (clockwise) {
        if (sweep >= -FULL_CIRCLE_EPS)
            sweep -= 2.0f * (float)M_PI;
    } else if (sweep <= FULL_CIRCLE_EPS) {
        sweep += 2.0f * (float)M_PI;
    }
    float r = arc->r0 > arc->r1 ? arc->r0 : arc->r1;
    /* a chord of angle a has sagitta r(1 - cos(a/2)) <= tol; for tol >= r any chord will do */
    float max_angle = tolerance >= r ? (float)M_PI : 2.0f * acosf(1.0f - tolerance / r);
    if (!(max_angle > 1.0e-6f))  /* acos near 1 loses precision in floats */
        max_angle = 2.0f * sqrtf(2.0f * tolerance / r);
    float n = ceilf(fabsf(sweep) / max_angle);
    if (n < 1.0f)
        n = 1.0f;
    if (n > ARC_MAX_SEGMENTS)
        n = ARC_MAX_SEGMENTS;
    arc->segments = (uint16_t)n;
    arc->angle0 = atan2f(sy, sx);
    arc->sweep = sweep;
    for (uint8_t a = 0; a < N_AXIS; a++) {
        arc->center[a] = center[a];
        arc->target[a] = target[a];
    }
    return STATUS_OK;
}

void arc_point(const arc_t *arc, uint16_t k, float *out)
{
    if (k >= arc->segments) {
        out[0] = arc->target[0];
        out[1] = arc->target[1];
        return;
    }
    float f = (float)k / (float)arc->segments;
    float ang = arc->angle0 + arc->sweep * f;
    float r = arc->r0 + (arc->r1 - arc->r0) * f;
    out[0] = arc->center[0] + r * cosf(ang);
    out[1] = arc->center[1] + r * sinf(ang);
}
