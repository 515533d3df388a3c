/* Timer2 in CTC mode at 250 kHz (4 us resolution). A 20 ms frame is a high
 * part (the pulse) and a low part, each cut into compare intervals of at most
 * 250 ticks. Every pulse edge is made by the compare-output hardware at a
 * compare match ("set OC2A on match" for the interval that ends in the rising
 * edge, "clear on match" for the one ending in the falling edge; the opposite,
 * no-op, mode in between), so the width has no interrupt jitter on the chip:
 * the interrupt only loads the next interval right after a match, and every
 * interval is at least 64 ticks, far longer than any interrupt latency.
 * simavr drives PB3 from the compare unit too, but it restarts the counter on
 * every OCR2A/TCCR2A write, so in the simulator each interval is stretched by
 * the interrupt latency (a few us per edge); the chip has no such error.
 * Boards whose servo pin is not OC2A set the pin from this interrupt instead
 * (SERVO_OC2A unset in the board header).
 * A pen move may be slewed ($64/$65): at each frame start the width steps
 * toward its target by a fixed number of ticks, so the pen travels at that
 * rate instead of dropping onto the paper (a fast drop leaves a dot).
 * The same interrupt keeps the millisecond timebase, and samples the inputs
 * on boards without pin-change wiring. */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <util/atomic.h>
#include "config.h"
#include "inputs.h"
#include "servo.h"

#define TICK_US 4
#define FRAME_TICKS 5000  /* 20 ms */
#define MAX_INTERVAL 250
#define MIN_INTERVAL 64
#define COM_SET ((1 << COM2A1) | (1 << COM2A0))
#define COM_CLEAR (1 << COM2A1)

static volatile uint16_t pulse_ticks;
static volatile uint16_t target_ticks; /* where a slewed move ends */
static volatile uint16_t slew_ticks;   /* width change per 20 ms frame */
static uint16_t width_us;
static uint8_t high;          /* level after the current interval's match */
static uint16_t remaining;    /* ticks left in the current part, including the current interval */
static uint8_t interval;      /* ticks of the interval now running */
static volatile uint32_t ms;
static uint16_t us_frac;

/* choose the next interval and the output mode for its match */
static void load_next(void)
{
    uint16_t next = remaining;
    if (next > MAX_INTERVAL)
        next = next >= MAX_INTERVAL + MIN_INTERVAL ? MAX_INTERVAL : next / 2;
    interval = (uint8_t)next;
    uint8_t edge = next == remaining;  /* the part ends with this match */
    uint8_t set = edge ? !high : high; /* edge: change level; otherwise keep it */
    OCR2A = (uint8_t)(next - 1);
#ifdef SERVO_OC2A
    TCCR2A = (uint8_t)((1 << WGM21) | (set ? COM_SET : COM_CLEAR));
#else
    (void)set;
    TCCR2A = 1 << WGM21;
#endif
}

ISR(TIMER2_COMPA_vect)
{
#ifndef SERVO_OC2A
    /* a pin without the compare output: set the level the match just made
     * (a few us late, the same for both edges, so the width holds) */
    IO_SET(SERVO, high ^ (remaining == interval));
#endif
    /* the rest (~100 cycles) may be interrupted: run with interrupts shut it
     * delayed a step tick due meanwhile by as much, and a step edge ~140
     * cycles late is a step period of 180 at 50 kHz. Not re-entered: the
     * next compare is at least MIN_INTERVAL ticks (256 us) away; the state
     * here is this interrupt's own, and the inputs are polled with
     * interrupts shut again (they raise the same flags as the UART's). */
    sei();
    us_frac += (uint16_t)interval * TICK_US;
    while (us_frac >= 1000) {
        us_frac -= 1000;
        ms++;
    }
    remaining -= interval;
    if (remaining == 0) {  /* the edge just happened in hardware */
        high = !high;
        /* a new frame: one slew step (a compare and an add, ~20 cycles once
         * per 20 ms; the width stays fixed within the frame) */
        if (high && pulse_ticks != target_ticks) {
            uint16_t p = pulse_ticks, t = target_ticks, d = slew_ticks;
            pulse_ticks = p < t ? (t - p > d ? p + d : t) : (p - t > d ? p - d : t);
        }
        remaining = high ? pulse_ticks : (uint16_t)(FRAME_TICKS - pulse_ticks);
    }
    load_next();
#ifndef INPUTS_PCINT
    cli();
    inputs_poll();
#endif
}

uint32_t timebase_ms(void)
{
    uint32_t v;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { v = ms; }
    return v;
}

void servo_init(void)
{
    IO_OUTPUT(SERVO);
    IO_LOW(SERVO);
    servo_set_us(1000);
    high = 0;
    remaining = 1000; /* a short low part first */
    load_next();
    TIMSK2 = 1 << OCIE2A;
    TCCR2B = 1 << CS22; /* clk/64 */
}

void servo_set_us(uint16_t us) { servo_move(us, 0); }

void servo_move(uint16_t us, uint16_t ms)
{
    /* us is $60 or $61: settings_set keeps both within 500-2500 */
    uint16_t span = width_us > us ? width_us - us : us - width_us;
    width_us = us;
    /* ticks per 20 ms frame for the whole span in about `ms` (at least
     * one): span / TICK_US * 20 / ms, in 16 bits (span <= 2000); no time:
     * the whole way at the next frame (the width only counts from there) */
    uint16_t step = ms ? (uint16_t)(span * (20 / TICK_US) / ms + 1) : 1000;
    uint16_t t = (uint16_t)((us + TICK_US / 2) / TICK_US);
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        target_ticks = t;
        slew_ticks = step;
    }
}

uint16_t servo_get_us(void) { return width_us; }
