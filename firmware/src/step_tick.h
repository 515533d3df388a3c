/* Which boards run the step tick's common path in assembly (step_tick.S)
 * and the state it shares with stepper.c. Assembler-safe: step_tick.S
 * includes it (and through config.h the board header) to take its pins.
 *
 * The assembly tick serves step/dir boards whose two step pins share a port
 * in I/O space (one `out` to PINx toggles both) and whose direction pins
 * are in the low I/O space too (sbi/cbi): uno-cnc-shield and
 * mega-ramps14. The others (uno-uln2003 and mega-l298n with their phase
 * tables, mega-stepdir with its step pins on two ports, one outside I/O
 * space) keep the C tick in stepper.c. */
#ifndef STEP_TICK_H
#define STEP_TICK_H
#include "config.h"

#if DRIVE_KIND == DRIVE_STEPDIR /* (coil boards name no step pins) */
/* (ports A-G are in the low I/O space, where sbi/cbi reach) */
#define STEP_TICK_ASM (IO_SAME_PORT(X_STEP, Y_STEP) && IO_PORT_NUM(X_STEP) <= IO_PORT_NUM_G && \
                       IO_PORT_NUM(X_DIR) <= IO_PORT_NUM_G && IO_PORT_NUM(Y_DIR) <= IO_PORT_NUM_G)
#else
#define STEP_TICK_ASM 0
#endif

/* segment.h's structs as step_tick.S reads them (stepper.c checks each) */
#define SEG_EVENTS_AT 0
#define SEG_PERIOD_AT 2
#define SEG_BLOCK_AT 4
#define SEG_FLAGS_AT 6
#define SEG_FIRST_BIT 0
#define BLK_STEPS_AT 0
#define BLK_EVENTS_AT 4
#define BLK_DIR_AT 6

/* tick_state_t's fields, for step_tick.S (stepper.c checks each) */
#define TICK_POSITION_AT 0
#define TICK_COUNTER_AT (4 * N_AXIS)
#define TICK_STEPS_AT (6 * N_AXIS)
#define TICK_EVENTS_AT (8 * N_AXIS)
#define TICK_K_AT (8 * N_AXIS + 2)
#define TICK_LEFT_AT (8 * N_AXIS + 4)

#ifdef __ASSEMBLER__
#define tick_position (tick + TICK_POSITION_AT)
#define tick_counter (tick + TICK_COUNTER_AT)
#define tick_steps (tick + TICK_STEPS_AT)
#define tick_events (tick + TICK_EVENTS_AT)
#define tick_k (tick + TICK_K_AT)
#define tick_left (tick + TICK_LEFT_AT)
#else
#include <stdint.h>
/* The tick's state (stepper.c defines it; step_tick.S reads its fields at
 * the offsets above). */
typedef struct {
    int32_t position[N_AXIS]; /* motor steps at the end of the block under way */
    int16_t counter[N_AXIS];  /* Bresenham: 16-bit, blocks are at most PLAN_MAX_EVENTS */
    int16_t steps[N_AXIS];    /* the block's |steps| and events, copied from its */
    int16_t events;           /* step_block_t when it starts: one load each a tick */
    uint16_t k;               /* the block's events up to the end of the segment under way */
    uint16_t left;            /* events left in that segment */
} tick_state_t;
extern tick_state_t tick;
extern uint8_t tick_dir_invert; /* $3, for step_tick.S's direction pins */
#endif
#endif
