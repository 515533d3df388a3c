#include "config.h"
#include "plan_split.h"
#include "planner.h"
#include "settings.h"

uint8_t plan_line_split(const float *target, float feed, uint8_t flags, uint8_t (*room)(void))
{
    if (!room())
        return 0;
    /* plan_line finds out whether the move fits; the split is the rare case */
    uint16_t pieces = plan_line(target, feed, flags);
    if (pieces < 2)
        return 1;
    int32_t from_steps[N_AXIS];
    float from[N_AXIS], p[N_AXIS];
    plan_get_position(from_steps);
    for (uint8_t a = 0; a < N_AXIS; a++)
        from[a] = (float)from_steps[a] / settings.steps_per_mm[a];
    for (uint16_t k = 1; k <= pieces; k++) {
        for (uint8_t a = 0; a < N_AXIS; a++)
            p[a] = k == pieces ? target[a] : from[a] + (target[a] - from[a]) * (float)k / (float)pieces;
        if (!room())
            return 0;
        plan_line(p, feed, flags);
    }
    return 1;
}
