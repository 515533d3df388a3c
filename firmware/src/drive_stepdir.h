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

/* DRIVE_X / DRIVE_Y bits whose pulse is up: a general purpose I/O register
 * (one cycle to read or write in the step interrupts) */
#define drive_pulsing GPIOR2

/* Both step pins on one port: an axis's bit is its pin's bit, so a step
 * is one write of the bits to PINx (a toggle: both edges at once). */
#define DRIVE_ONE_PORT IO_SAME_PORT(X_STEP, Y_STEP)
#define DRIVE_X (DRIVE_ONE_PORT ? IO_MASK(X_STEP) : 1u)
#define DRIVE_Y (DRIVE_ONE_PORT ? IO_MASK(Y_STEP) : 2u)

/* 1 cycle on a shared port (one write), 2 per axis on separate ports */
static inline __attribute__((always_inline)) void drive_step(uint8_t bits)
{
    if (DRIVE_ONE_PORT) {
        IO_PINREG(X_STEP) = bits; /* writing 0 toggles nothing */
    } else {
        if (bits & 1)
            IO_TOGGLE(X_STEP);
        if (bits & 2)
            IO_TOGGLE(Y_STEP);
    }
    drive_pulsing = bits;
}

static inline __attribute__((always_inline)) void drive_step_end(void)
{
    if (DRIVE_ONE_PORT)
        IO_PINREG(X_STEP) = drive_pulsing;
    else
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
