/* Homing steps at a constant rate from the main loop (the step interrupt
 * is idle), timed by busy waits, watching the switches before every step.
 * Each axis stops on its own switch. */
#include <util/delay.h>
#include "config.h"
#include "homing.h"
#include "inputs.h"
#include "machine.h"
#include "planner.h"
#include "realtime.h"
#include "settings.h"
#include "status.h"
#include "stepper.h"

static const uint8_t axis_pin[N_AXIS] = {PIN_X_LIMIT, PIN_Y_LIMIT};

static void wait_us(uint16_t us)
{
    while (us >= 20) {
        _delay_us(18); /* the loop itself costs about 2 us */
        us -= 20;
    }
}

/* switches bounce: let them settle between phases ($26) */
static void settle(void)
{
    for (uint16_t i = 0; i < settings.homing_debounce_ms; i++) {
        machine_poll();
        _delay_us(990);
    }
}

/* One cartesian step on axis a; CoreXY turns it into a step of both motors. */
static void cart_step(uint8_t a, uint8_t negative)
{
    if (!settings.corexy) {
        stepper_pulse((uint8_t)(1 << a), negative ? (uint8_t)(1 << a) : 0);
        return;
    }
    uint8_t dir = 0;
    if (negative)
        dir |= 1;               /* A = X + Y */
    if (a == 0 ? negative : !negative)
        dir |= 2;               /* B = X - Y */
    stepper_pulse(3, dir);
}

/* Move the axes in mask toward their home switches (toward = 1) or away,
 * until each switch reads `want_closed`, at most max_mm. Returns the mask of
 * axes that did not get there. */
static uint8_t move_until(uint8_t mask, uint8_t toward, uint8_t want_closed, float rate_mm_min, float max_mm)
{
    uint32_t max_steps[N_AXIS], done[N_AXIS] = {0, 0};
    float spm = settings.steps_per_mm[0] > settings.steps_per_mm[1] ? settings.steps_per_mm[0]
                                                                      : settings.steps_per_mm[1];
    float rate = rate_mm_min / 60.0f * spm;
    /* CoreXY: an X and a Y step in the same tick would be two pulses on one
     * motor at once; take the axes in turns at twice the tick rate instead */
    uint8_t turns = settings.corexy ? 2 : 1;
    rate *= turns;
    uint16_t period = rate > 50.0f ? (uint16_t)(1.0e6f / rate) : 20000;
    for (uint8_t a = 0; a < N_AXIS; a++)
        max_steps[a] = (uint32_t)(max_mm * settings.steps_per_mm[a] + 0.5f);
    for (uint8_t tick = 0; mask; tick++) {
        machine_poll();
        if (mach.abort)
            return mask;
        uint8_t closed = inputs_home_switches();
        for (uint8_t a = 0; a < N_AXIS; a++) {
            if (!(mask & (1 << a)))
                continue;
            if (((closed & axis_pin[a]) != 0) == want_closed) {
                mask &= (uint8_t)~(1 << a);
                continue;
            }
            if (turns == 2 && (tick & 1) != a)
                continue;
            if (done[a]++ >= max_steps[a])
                return mask;
            uint8_t to_min = (settings.homing_dir_mask >> a) & 1;
            cart_step(a, toward ? to_min : !to_min);
        }
        wait_us(period);
    }
    return 0;
}

uint8_t homing_run(void)
{
    const uint8_t both = (1 << N_AXIS) - 1;
    float span = settings.max_travel[0] > settings.max_travel[1] ? settings.max_travel[0] : settings.max_travel[1];
    float pull = settings.homing_pulloff > 0.2f ? settings.homing_pulloff : 0.2f;
    uint8_t code = 0;
    stepper_enable(1);
    inputs_homing(1);
    mach.homing = 1;
    /* already on a switch: back off first */
    if (move_until(both, 0, 0, settings.homing_seek, pull * 4.0f))
        code = ALARM_HOMING_PULLOFF;
    else if (move_until(both, 1, 1, settings.homing_seek, span * 1.5f))
        code = ALARM_HOMING_NOT_FOUND;
    else if ((settle(), move_until(both, 0, 0, settings.homing_feed, pull * 4.0f)))
        code = ALARM_HOMING_PULLOFF;
    else if ((settle(), move_until(both, 1, 1, settings.homing_feed, pull * 5.0f)))
        code = ALARM_HOMING_NOT_FOUND;
    if (!code) {
        /* The switch closed on the last step: the trip point (machine 0, or
         * the maximum travel) lies between this step and the one before, and
         * we call the last open position the trip point. */
        int32_t cart[N_AXIS], motor[N_AXIS];
        for (uint8_t a = 0; a < N_AXIS; a++) {
            uint8_t to_min = (settings.homing_dir_mask >> a) & 1;
            int32_t edge = to_min ? 0 : (int32_t)(settings.max_travel[a] * settings.steps_per_mm[a] + 0.5f);
            cart[a] = to_min ? edge - 1 : edge + 1;
        }
        plan_motor_steps(cart, motor);
        stepper_set_position(motor);
        settle();
        /* want_closed = 2 never matches: travel exactly the pull-off */
        move_until(both, 0, 2, settings.homing_feed, settings.homing_pulloff);
        for (uint8_t a = 0; a < N_AXIS; a++) { /* plus the step from the trip point back to its edge */
            cart_step(a, !((settings.homing_dir_mask >> a) & 1));
            wait_us(200);
        }
    }
    mach.homing = 0;
    inputs_homing(0);
    if (mach.abort && !code)
        code = ALARM_HOMING_RESET;
    return code;
}
