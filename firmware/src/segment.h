/* Step segments: the main loop cuts the planner's trapezoids into short
 * pieces of constant step rate; the step interrupt only runs integer
 * Bresenham over them. Pure (shared with the ISR through the ring below). */
#ifndef SEGMENT_H
#define SEGMENT_H
#include <stdint.h>
#include "config.h"
#include "planner.h"

#define SEG_FIRST 0x01      /* first segment of a block: reset Bresenham, set direction */

typedef struct {
    int16_t steps[N_AXIS];  /* |motor steps|, at most PLAN_MAX_EVENTS */
    int16_t events;
    uint8_t dir_negative;   /* bit per motor */
    PLAN_LINE_FIELD(line);  /* its planner block's N number */
} step_block_t;

typedef struct {
    uint16_t events;        /* step events in this segment */
    uint16_t period;        /* step timer ticks per event, minus 1 (the OCR1A value) */
    step_block_t *block;    /* its block in step_blocks (a pointer: no index multiply in the ISR) */
    uint8_t flags;
} segment_t;

extern segment_t seg_ring[SEG_SIZE];
extern step_block_t step_blocks[SEG_SIZE];
extern volatile uint8_t seg_head, seg_tail; /* free-running, masked with SEG_SIZE */

void seg_reset(void);
/* Prepare segments while there is room; returns 1 if any was added. */
uint8_t seg_fill(void);
/* Feed hold: decelerate to a stop along the path (and undo with 0). */
void seg_hold(uint8_t on);
/* 1 once a hold has brought the prepared motion to a stop. */
uint8_t seg_hold_reached(void);
/* Forget the rest of the block being prepared (jog cancel after a hold). */
void seg_drop_block(void);
/* N number of the block the steppers are executing: the segment under way,
 * else (a hold has drained them) the block being prepared; 0 when idle.
 * Not the block being prepared while segments run: that one is up to
 * SEG_SIZE - 1 short blocks ahead of the pen. Main loop only. */
plan_line_t seg_exec_line(void);
/* Speed of the most recently prepared segment, mm/s. */
float seg_speed(void);
#endif
