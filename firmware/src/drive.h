/* The stepper output seam: stepper.c (Bresenham, position) and homing.c
 * decide which axes step and which way; every motor pin write happens behind
 * these calls, so a board may have step/dir drivers or four coil wires.
 *
 *   drive_init()            outputs configured, motors off
 *   drive_apply_settings()  $2 step invert, $3 dir invert, $4 enable invert
 *   drive_set_dir(neg)      bit0 X, bit1 Y: 1 = the next steps go negative;
 *                           called before a block's first step
 *   drive_step(bits)        one step now on the axes in bits, an OR of
 *                           DRIVE_X / DRIVE_Y (step/dir: the pulse rises;
 *                           four-wire: the next coil state)
 *   drive_step_end()        step/dir: the pulse falls; four-wire: nothing
 *   drive_enable(on)        enable line, or coils energized/de-energized
 *                           (a four-wire drive keeps its phase either way)
 *   DRIVE_PULSED            1: drive_step_end must follow drive_step after $0 us
 *   DRIVE_X, DRIVE_Y        each axis's bit in drive_step's argument: the
 *                           step pins' own port bits where both share a port
 *                           (the interrupt writes its step bits to the port
 *                           as they are), else 1 and 2
 *
 * The hot calls (step, step_end, set_dir) are static inline in the drive kind's
 * header so the step interrupt pays no call. */
#ifndef DRIVE_H
#define DRIVE_H
#include <stdint.h>
#include "config.h"

void drive_init(void);
void drive_apply_settings(void);
void drive_enable(uint8_t on);

#if DRIVE_KIND == DRIVE_STEPDIR
#include "drive_stepdir.h"
#else
#include "drive_coils.h"
#endif

#endif
