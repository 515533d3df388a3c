/* Look-ahead motion planner: a ring of straight moves in motor steps with
 * junction speeds from the junction-deviation rule and entry speeds that let
 * every block still stop by the end of the queue. Pure (main loop only). */
#ifndef PLANNER_H
#define PLANNER_H
#include <stdint.h>
#include <string.h>
#include "config.h"
#include "float_bits.h"

#define PLAN_MAX_EVENTS 30000 /* the step interrupt counts in 16 bits: longer moves are split */
#define PLAN_MAX_STEPS 1.0e9f /* machine positions stay well inside int32 */
/* Squared speeds in units of 1/PLAN_SQR_SCALE (mm/s)^2, rounded down (so
 * never above a limit), saturated at PLAN_SQR_MAX (4096 mm/s) so that a sum
 * of two never overflows. */
typedef uint32_t plan_sqr_t;
#define PLAN_SQR_SHIFT 6     /* the scale is a power of two: conversions add to the exponent */
#define PLAN_SQR_SCALE ((float)(1 << PLAN_SQR_SHIFT))
#define PLAN_SQR_MAX (1UL << 30)
plan_sqr_t plan_sqr_from_float(float v_sqr);
float plan_sqr_to_float(plan_sqr_t v);

/* Float order by integer compare: plan_lt(a, b) exactly when a < b, for
 * floats of which at least one is not negative (IEEE bits read as a signed
 * integer order the values so; two negative ones would compare reversed),
 * neither NaN; -0 sorts just below +0, which no caller minds. The main loop
 * compares ~35 floats a line; the float library's compare is ~80 cycles on
 * the AVR with its call, this a few (a constant side is folded). */
static inline uint8_t plan_lt(float a, float b)
{
    return (int32_t)float_bits(a) < (int32_t)float_bits(b);
}
#define PB_RAPID 0x01
#define PB_JOG 0x02

/* A non-negative float in 16 bits: its IEEE single bits 30..15 (exponent and
 * the top 7 mantissa bits; the sign is always 0), cut toward zero, so never
 * above the value and within 2^-7 of it (a speed from its square: 2^-8).
 * Decoding is byte moves, no arithmetic. */
typedef uint16_t plan_f16_t;
plan_f16_t plan_f16_from_float(float v);
float plan_f16_to_float(plan_f16_t h);

/* The N number of a block's line (0: none). GRBL's limit is 10,000,000
 * (gcode.c answers error:27 above it), so 24 bits hold it: 3 bytes a block
 * instead of 4 is what lets the 328P keep 33 blocks. The host has no 24-bit
 * integer; a 24-bit field takes the same 3 bytes in its packed block. */
#ifdef __AVR__
typedef __uint24 plan_line_t;
#define PLAN_LINE_FIELD(name) plan_line_t name
#else
typedef uint32_t plan_line_t;
#define PLAN_LINE_FIELD(name) plan_line_t name : 24
#endif

/* A queued move, 24 bytes: only what the queue and the segment preparer
 * need. The planner passes run on every queued block for every new one, so
 * they work on squared speeds in fixed point (plan_sqr_t: integer adds and
 * compares); the length and acceleration are not stored in it but derived
 * from the steps when needed (plan_block_motion: once when the block is
 * queued, once when its segments are prepared), so the same RAM holds about
 * twice the blocks of a float block. The 2560 and the host library keep
 * that geometry beside the ring instead (config.h PLAN_CACHE_MOTION). */
typedef struct {
    int16_t steps[N_AXIS];    /* signed motor steps, |steps| <= PLAN_MAX_EVENTS;
                               * step events: the largest |steps| (plan_events) */
    plan_sqr_t accel_dist2;   /* 2 * accel * mm: speed^2 gained over the block */
    plan_sqr_t entry_sqr;     /* planned entry speed squared */
    plan_sqr_t max_entry_sqr; /* junction limit squared */
    plan_f16_t nominal_sqr;   /* cruise speed squared, (mm/s)^2, overrides applied */
    uint16_t feed;            /* programmed feed, mm/min rounded (unused by rapids) */
    uint8_t flags;
    PLAN_LINE_FIELD(line);    /* the N number of the line it comes from, 0 none */
} plan_block_t;

/* The float view of a block's geometry (main loop only), from its steps
 * with the present axis settings: one square root and one division (the
 * length's reciprocal; the acceleration comes from accel_dist2). */
typedef struct {
    float mm;                 /* length in mm */
    float events_per_mm;
    float accel;              /* mm/s^2 along the move as accel_dist2 stands for it
                               * (at most 2^-12 below the exact one) */
    float inv_accel;          /* 1 / the exact one, so the segment preparer multiplies */
} plan_motion_t;
void plan_block_motion(const plan_block_t *b, plan_motion_t *m);
/* The 328P derives a block's motion in two steps: plan_block_motion gives
 * the length, and this the rest (events per mm, acceleration) when the
 * segment preparer first needs it; a block cruised through to its end needs
 * only the length (a division and ~5 multiplies a block less). A no-op
 * where plan_block_motion gives the cached whole. */
#if PLAN_CACHE_MOTION
static inline void plan_motion_complete(const plan_block_t *b, plan_motion_t *m)
{
    (void)b;
    (void)m;
}
#else
void plan_motion_complete(const plan_block_t *b, plan_motion_t *m);
#endif

void plan_reset(void);
/* a $100-$121 setting may have changed (the planner is empty): its reciprocals are
 * derived again for the next block (plan_reset does this too) */
void plan_settings_changed(void);
/* Planner position in cartesian steps, e.g. after homing or an abort. */
void plan_set_position(const int32_t *steps);
void plan_get_position(int32_t *steps);
uint8_t plan_free(void);
uint8_t plan_count(void);
/* Queue a move to target (machine mm) at feed (mm/min; ignored with PB_RAPID).
 * The caller makes sure plan_free() > 0. Returns 1 when queued, 0 for a move
 * too short for a step; for one that needs more than PLAN_MAX_EVENTS step
 * events nothing is queued and it returns into how many equal pieces the
 * caller must cut it (at least 2): from its motor step events, so that none
 * comes out above the limit (the steps of the pieces round each on their
 * own). */
uint16_t plan_line(const float *target, float feed, uint8_t flags);
/* The N number plan_line gives the blocks it queues from now on (0: none). */
void plan_set_line_number(plan_line_t n);
plan_block_t *plan_current(void);    /* oldest block, or 0 */
uint16_t plan_events(const plan_block_t *b); /* step events of a block */
/* The lazy backward pass (planner.c, lazy_append): a new block behind a
 * queue planned down to a stop adds its accel_dist2 to one sum instead of
 * every queued entry. ~1.1 kB of flash, which the 328P has not got; the
 * entries are the same either way (tests/e2e/test_motion_model.py holds the
 * Uno's eager ones to the host library's lazy ones). */
#define PLAN_LAZY PLAN_CACHE_MOTION
/* A queued block's planned entry speed squared (with PLAN_LAZY, entry_sqr
 * of the newest blocks is kept relative to a sum the newer blocks add). */
#if PLAN_LAZY
plan_sqr_t plan_entry_sqr(const plan_block_t *b);
#else
static inline plan_sqr_t plan_entry_sqr(const plan_block_t *b) { return b->entry_sqr; }
#endif
float plan_next_entry_sqr(void);     /* entry of the block after the oldest; 0 if none */
void plan_discard_current(void);
/* Highest exit speed^2 the executing block can still reach (segment preparer). */
void plan_set_exec_exit_limit(float v_sqr);
/* GRBL's realtime overrides, percent (feed 10..200, rapid 25/50/100; 100 =
 * as programmed): the nominal speed of every queued block, the executing
 * one included, is recomputed (feed_pct for G1/G2/G3, rapid_pct for
 * G0/G28; jogs keep theirs), junction limits are capped by the new speeds,
 * and the queue is replanned. Later blocks are planned with them too. A
 * junction capped by a lower speed is not raised again when the speed
 * rises (it stays safe, merely slower, for the blocks already queued).
 * The recompute is done a few blocks at a time, oldest first: the first
 * slice here, the rest by plan_override_step, once per main-loop pass. */
void planner_set_overrides(uint8_t feed_pct, uint8_t rapid_pct);
/* The next slice of an override change's recompute (a no-op when none is
 * under way); 1 while blocks are left. */
uint8_t plan_override_step(void);
/* Motor steps for cartesian steps (CoreXY: A = X + Y, B = X - Y). */
void plan_motor_steps(const int32_t *cart, int32_t *motor);
void plan_cart_from_motor(const int32_t *motor, int32_t *cart);
#endif
