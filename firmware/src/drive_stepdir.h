/* Step/dir drivers: the hot half of the seam (drive.h), inline.
 * A step pulse is a toggle of the step pins away from their idle level and
 * back (writing PINx toggles in one cycle); $2 sets the idle level. */
#ifndef DRIVE_STEPDIR_H
#define DRIVE_STEPDIR_H
#include <avr/io.h>
#include <stdint.h>
#include <util/atomic.h>
#include "config.h"
#include "settings.h"

#define DRIVE_PULSED 1

extern uint8_t drive_pulsing; /* axes whose pulse is up */

/* 2 cycles per axis on separate ports, 3 on a shared one (one write) */
static inline __attribute__((always_inline)) void drive_step(uint8_t axes)
{
    if (IO_SAME_PORT(X_STEP, Y_STEP)) {
        uint8_t bits = 0;
        if (axes & 1)
            bits |= IO_MASK(X_STEP);
        if (axes & 2)
            bits |= IO_MASK(Y_STEP);
        IO_PINREG(X_STEP) = bits; /* both edges in one write */
    } else {
        if (axes & 1)
            IO_TOGGLE(X_STEP);
        if (axes & 2)
            IO_TOGGLE(Y_STEP);
    }
    drive_pulsing = axes;
}

static inline __attribute__((always_inline)) void drive_step_end(void)
{
    drive_step(drive_pulsing);
    drive_pulsing = 0;
}

/* Called between pulses (the step pins are idle), so no pin is shared with
 * a pulse in flight; the driver's setup time is the rest of the period.
 * Inline: a call from the step interrupt would make it save every
 * call-clobbered register on every tick. */
static inline __attribute__((always_inline)) void drive_set_dir(uint8_t negative_mask)
{
    uint8_t level = negative_mask ^ settings.dir_invert; /* 1 = HIGH: negative at $3=0 */
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        IO_SET(X_DIR, level & 1);
        IO_SET(Y_DIR, level & 2);
    }
}

#endif
