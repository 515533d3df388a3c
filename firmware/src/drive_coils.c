/* Four-wire drives: coil sequences instead of step pulses. Each axis's four
 * coil pins must share one port (its table holds that port's bits).
 *
 * One 8-state table serves both kinds; A, B, C, D are the coil pins in the
 * board header's sequence order: A, AB, B, BC, C, CD, D, DA.
 * - unipolar (ULN2003 + 28BYJ-48): the four coil ends of the centre-tapped
 *   motor; half-step, all eight states (4096 half-steps per output turn).
 * - bipolar (L298N, L293D): A/C drive coil 1 forward/reverse, B/D coil 2;
 *   half-step uses all eight states, full-step two-phase-on the odd ones
 *   (two coils always on: full torque).
 * The phase is the rotor's position in the sequence: de-energizing the coils
 * (idle delay, $SLP-like motors off, alarm) keeps it, and it lives in a
 * .noinit section guarded by a check byte, so a watchdog reset keeps it too.
 * The next move continues from the state the rotor is in: no step skipped
 * or doubled. */
#include <avr/io.h>
#include <util/atomic.h>
#include "drive.h"
#include "settings.h"

#if DRIVE_KIND != DRIVE_STEPDIR

#define SEQ(a, b, c, d) {a, a | b, b, b | c, c, c | d, d, d | a}
const uint8_t coil_x[8] = SEQ(IO_MASK(X_COIL_A), IO_MASK(X_COIL_B), IO_MASK(X_COIL_C), IO_MASK(X_COIL_D));
const uint8_t coil_y[8] = SEQ(IO_MASK(Y_COIL_A), IO_MASK(Y_COIL_B), IO_MASK(Y_COIL_C), IO_MASK(Y_COIL_D));

coil_state_t coil_state __attribute__((section(".noinit")));
uint8_t coil_delta[2] = {COIL_STRIDE, COIL_STRIDE};
uint8_t coil_on;

static void write_coils(void)
{
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        uint8_t x = coil_on ? coil_x[coil_state.phase[0]] : 0;
        uint8_t y = coil_on ? coil_y[coil_state.phase[1]] : 0;
        IO_PORT(X_COIL_A) = (uint8_t)((IO_PORT(X_COIL_A) & ~COIL_X_MASK) | x);
        IO_PORT(Y_COIL_A) = (uint8_t)((IO_PORT(Y_COIL_A) & ~COIL_Y_MASK) | y);
    }
}

void drive_init(void)
{
    uint8_t valid = (uint8_t)(coil_state.phase[0] ^ coil_state.phase[1] ^ 0xA5) == coil_state.check &&
                    coil_state.phase[0] < 8 && coil_state.phase[1] < 8;
    if (!valid) { /* power-up: the rotor is pulled to the first state of the sequence */
        coil_state.phase[0] = coil_state.phase[1] = COIL_STRIDE - 1;
        coil_state.check = 0xA5;
    }
    coil_on = 0;
    write_coils();
    IO_DDR(X_COIL_A) |= COIL_X_MASK;
    IO_DDR(Y_COIL_A) |= COIL_Y_MASK;
}

/* $2 (step invert) and $4 (enable invert) have no meaning without step and
 * enable pins; $3 is drive_set_dir's (drive_coils.h). */
void drive_apply_settings(void) {}

void drive_enable(uint8_t on)
{
    coil_on = on;
    write_coils();
}

#endif
