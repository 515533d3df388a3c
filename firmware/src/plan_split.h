/* One straight move into the planner, in equal pieces when it is too long
 * for the 16-bit step counters: the firmware's line_to and the host
 * estimator (host/motion.c) share it. Pure. */
#ifndef PLAN_SPLIT_H
#define PLAN_SPLIT_H
#include <stdint.h>

/* room(): wait until the planner has a free block; 0 gives up (an abort).
 * Returns 1 when everything was queued. */
uint8_t plan_line_split(const float *target, float feed, uint8_t flags, uint8_t (*room)(void));
#endif
