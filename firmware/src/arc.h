/* Cuts an arc into chords whose sagitta stays within the arc tolerance.
 * Pure. Each chord end is computed from the start angle directly (no
 * accumulated rotation), and the last one is the exact target. */
#ifndef ARC_H
#define ARC_H
#include <stdint.h>
#include "config.h"

#define ARC_MAX_SEGMENTS 20000

typedef struct {
    float center[N_AXIS];
    float target[N_AXIS];
    float r0, r1;          /* radius at start and end (they may differ slightly) */
    float angle0, sweep;   /* start angle and signed travel, radians */
    uint16_t segments;
} arc_t;

/* 0 on success; ERR_INVALID_TARGET for a degenerate arc. */
uint8_t arc_init(arc_t *arc, const float *start, const float *target, const float *center,
                 uint8_t clockwise, float tolerance);
/* End of chord k (1..segments). */
void arc_point(const arc_t *arc, uint16_t k, float *out);
#endif
