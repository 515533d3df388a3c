/* Four-wire drives (ULN2003 unipolar, L298N/L293D bipolar): the hot half of
 * the seam (drive.h), inline. Each axis's four coil pins share one port; a
 * step writes the next entry of a precomputed 8-state table. */
#ifndef DRIVE_COILS_H
#define DRIVE_COILS_H
#include <avr/io.h>
#include <stdint.h>
#include "config.h"
#include "settings.h"

#define DRIVE_PULSED 0
#define DRIVE_X 1u /* drive_step's bits */
#define DRIVE_Y 2u

#if DRIVE_KIND == DRIVE_BIPOLAR && BIPOLAR_FULL_STEP
#define COIL_STRIDE 2  /* full step two-phase-on: the odd (two coils) states */
#else
#define COIL_STRIDE 1  /* half step: all eight states */
#endif

typedef struct {
    uint8_t phase[2];     /* 0..7 per axis: the state the rotor sits in */
    uint8_t check;        /* phase[0] ^ phase[1] ^ 0xA5: valid across a watchdog reset */
} coil_state_t;

extern coil_state_t coil_state;
extern uint8_t coil_delta[2];     /* +COIL_STRIDE or -COIL_STRIDE per axis */
extern uint8_t coil_on;           /* coils energized */
extern const uint8_t coil_x[8], coil_y[8]; /* port bits per state */

#define COIL_X_MASK (IO_MASK(X_COIL_A) | IO_MASK(X_COIL_B) | IO_MASK(X_COIL_C) | IO_MASK(X_COIL_D))
#define COIL_Y_MASK (IO_MASK(Y_COIL_A) | IO_MASK(Y_COIL_B) | IO_MASK(Y_COIL_C) | IO_MASK(Y_COIL_D))

/* about 14 cycles per stepping axis (table load and a port read-modify-write;
 * called with interrupts off, so the port write cannot race) */
static inline void drive_step(uint8_t axes)
{
    if (axes & DRIVE_X) {
        uint8_t p = (uint8_t)((coil_state.phase[0] + coil_delta[0]) & 7);
        coil_state.phase[0] = p;
        if (coil_on)
            IO_PORT(X_COIL_A) = (uint8_t)((IO_PORT(X_COIL_A) & ~COIL_X_MASK) | coil_x[p]);
    }
    if (axes & DRIVE_Y) {
        uint8_t p = (uint8_t)((coil_state.phase[1] + coil_delta[1]) & 7);
        coil_state.phase[1] = p;
        if (coil_on)
            IO_PORT(Y_COIL_A) = (uint8_t)((IO_PORT(Y_COIL_A) & ~COIL_Y_MASK) | coil_y[p]);
    }
    coil_state.check = (uint8_t)(coil_state.phase[0] ^ coil_state.phase[1] ^ 0xA5);
}

static inline void drive_step_end(void) {}

/* $3 reverses the sequence per axis, as it reverses a motor. Inline: see
 * drive_stepdir.h. */
static inline __attribute__((always_inline)) void drive_set_dir(uint8_t negative_mask)
{
    uint8_t neg = negative_mask ^ settings.dir_invert;
    coil_delta[0] = (neg & 1) ? (uint8_t)(8 - COIL_STRIDE) : COIL_STRIDE;
    coil_delta[1] = (neg & 2) ? (uint8_t)(8 - COIL_STRIDE) : COIL_STRIDE;
}

#endif
