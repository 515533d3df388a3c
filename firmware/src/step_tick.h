/* Which boards run the step tick's common path in assembly (step_tick.S)
 * and the state it shares with stepper.c. Assembler-safe: step_tick.S
 * includes it (and through config.h the board header) to take its pins.
 *
 * The assembly tick serves step/dir boards whose two step pins share a port
 * in I/O space (one `out` to PINx toggles both): uno-cnc-shield and
 * mega-ramps14. The others (uno-uln2003 and mega-l298n with their phase
 * tables, mega-stepdir with its step pins on two ports, one outside I/O
 * space) keep the C tick in stepper.c. */
#ifndef STEP_TICK_H
#define STEP_TICK_H
#include "config.h"

#if DRIVE_KIND == DRIVE_STEPDIR /* (coil boards name no step pins) */
#define STEP_TICK_ASM (IO_SAME_PORT(X_STEP, Y_STEP) && IO_PORT_NUM(X_STEP) <= IO_PORT_NUM_G)
#else
#define STEP_TICK_ASM 0
#endif

#ifndef __ASSEMBLER__
#include <stdint.h>
/* The tick's state, by name in step_tick.S (stepper.c defines it). */
extern uint16_t tick_left;              /* events left in the segment under way */
extern int16_t tick_counter[N_AXIS];    /* Bresenham: 16-bit, blocks are at most PLAN_MAX_EVENTS */
extern int16_t tick_steps[N_AXIS];      /* the block's |steps| and events, copied from its */
extern int16_t tick_events;             /* step_block_t when it starts: one load each a tick */
extern volatile int16_t tick_done[N_AXIS]; /* steps since the main loop last folded them */
/* step_tick.S's slow path, interrupts off: the segment under way is done;
 * load the next (its events) or stop the steppers (0). */
uint16_t stepper_tick_load(void);
#endif
#endif
