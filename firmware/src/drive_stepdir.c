/* Step/dir drivers (A4988, DRV8825, ...): step, direction and enable pins
 * from the board header. Direction as GRBL: with $3=0 a LOW direction pin
 * moves the axis positive; $3 inverts per axis. */
#include <avr/io.h>
#include <util/atomic.h>
#include "drive.h"
#include "settings.h"

#if DRIVE_KIND == DRIVE_STEPDIR

static uint8_t enabled;

void drive_init(void)
{
    IO_OUTPUT(X_STEP);
    IO_OUTPUT(Y_STEP);
    IO_OUTPUT(X_DIR);
    IO_OUTPUT(Y_DIR);
    IO_OUTPUT(X_ENABLE);
#ifdef Y_ENABLE
    IO_OUTPUT(Y_ENABLE);
#endif
    enabled = 0;
    drive_apply_settings();
}

void drive_apply_settings(void)
{
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        /* idle level of each step pin: low, or high where $2 inverts it */
        drive_pulsing = 0;
        IO_SET(X_STEP, settings.step_invert & 1);
        IO_SET(Y_STEP, settings.step_invert & 2);
    }
    drive_enable(enabled);
}

void drive_enable(uint8_t on)
{
    enabled = on;
    /* the enable line is active low unless $4 inverts it */
    uint8_t high = on == (settings.enable_invert != 0);
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        IO_SET(X_ENABLE, high);
#ifdef Y_ENABLE
        IO_SET(Y_ENABLE, high);
#endif
    }
}

#endif
