#include <avr/interrupt.h>
#include <avr/io.h>
#include <util/atomic.h>
#include <util/delay.h>
#include "ring.h"
#include "segment.h"
#include "settings.h"
#include "stepper.h"

static const uint8_t step_bit[N_AXIS] = {1 << X_STEP_BIT, 1 << Y_STEP_BIT};
static const uint8_t dir_bit[N_AXIS] = {1 << X_DIR_BIT, 1 << Y_DIR_BIT};

static volatile uint8_t running;
static volatile int32_t position[N_AXIS];   /* motor steps */
static uint8_t step_invert, dir_invert;     /* as port D bits */
static uint8_t pulse_ticks;                 /* Timer0 ticks (0.5 us) */
static uint8_t enabled;

/* state of the step interrupt */
static uint8_t pending_steps;   /* port bits to pulse at the next tick */
static uint8_t dir_bits;        /* port bits of the current block's direction */
static uint16_t seg_left;
static step_block_t *blk;
static int16_t counter[N_AXIS]; /* Bresenham: 16-bit, blocks are at most PLAN_MAX_EVENTS */

void stepper_apply_settings(void)
{
    step_invert = dir_invert = 0;
    for (uint8_t a = 0; a < N_AXIS; a++) {
        if (settings.step_invert & (1 << a))
            step_invert |= step_bit[a];
        if (settings.dir_invert & (1 << a))
            dir_invert |= dir_bit[a];
    }
    pulse_ticks = (uint8_t)(settings.pulse_us * 2 + 1); /* +1: the first tick may be partly gone */
    PORTD = (uint8_t)((PORTD & ~STEP_MASK) | step_invert);
    stepper_enable(enabled);
}

void stepper_init(void)
{
    DDRD |= STEP_MASK | DIR_MASK;
    DDRB |= 1 << ENABLE_BIT;
#ifdef BENCH_ISR_PIN
    DDRC |= 1 << 5;
#endif
    TCCR0A = 0;
    TCCR0B = 1 << CS01;          /* Timer0 free-running at 2 MHz: pulse-length clock */
    TCCR1A = 0;
    TCCR1B = 1 << WGM12;         /* CTC, clock off until a move starts */
    enabled = 0;
    stepper_apply_settings();
}

void stepper_enable(uint8_t on)
{
    enabled = on;
    /* the enable line is active low unless $4 inverts it */
    if (on != (settings.enable_invert != 0))
        PORTB &= ~(1 << ENABLE_BIT);
    else
        PORTB |= 1 << ENABLE_BIT;
}

uint8_t stepper_enabled(void) { return enabled; }
uint8_t stepper_busy(void) { return running; }

void stepper_start(void)
{
    if (running || seg_head == seg_tail)
        return;
    if (!enabled)
        stepper_enable(1);
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        pending_steps = 0;
        seg_left = 0;
        running = 1;
        /* simavr never fires a CTC timer whose compare value is 0: load one first */
        OCR1A = 100;
        TCNT1 = 0;
        TIFR1 = 1 << OCF1A;
        TIMSK1 = 1 << OCIE1A;
        TCCR1B = (1 << WGM12) | (1 << CS11);
    }
}

uint8_t stepper_halt(void)
{
    uint8_t was;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        TCCR1B = 1 << WGM12;
        TIMSK1 = 0;
        PORTD = (uint8_t)((PORTD & ~STEP_MASK) | step_invert);
        was = running;
        running = 0;
        /* steps counted but never pulsed: take them back so the position stays true */
        if (pending_steps & (1 << X_STEP_BIT))
            position[0] += (dir_bits & (1 << X_DIR_BIT)) ? -1 : 1;
        if (pending_steps & (1 << Y_STEP_BIT))
            position[1] += (dir_bits & (1 << Y_DIR_BIT)) ? -1 : 1;
        pending_steps = 0;
    }
    return was;
}

void stepper_get_position(int32_t *motor)
{
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        for (uint8_t a = 0; a < N_AXIS; a++)
            motor[a] = position[a];
    }
}

void stepper_set_position(const int32_t *motor)
{
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        for (uint8_t a = 0; a < N_AXIS; a++)
            position[a] = motor[a];
    }
}

void stepper_pulse(uint8_t mask, uint8_t dir_negative)
{
    uint8_t dirs = 0, steps = 0;
    for (uint8_t a = 0; a < N_AXIS; a++) {
        if (!(dir_negative & (1 << a)))
            dirs |= dir_bit[a];
        if (mask & (1 << a)) {
            steps |= step_bit[a];
            position[a] += (dir_negative & (1 << a)) ? -1 : 1;
        }
    }
    PORTD = (uint8_t)((PORTD & ~DIR_MASK) | (dirs ^ dir_invert));
    _delay_us(2); /* direction setup time before the edge */
    PORTD = (uint8_t)((PORTD & ~STEP_MASK) | (steps ^ step_invert));
    _delay_us(10);
    PORTD = (uint8_t)((PORTD & ~STEP_MASK) | step_invert);
}

/* One step event per tick: emit the pulse computed last tick (so its edge
 * has no jitter from the work below), then run Bresenham for the next one.
 * Directions change only after the pulse falls, a full period before the
 * next edge. */
ISR(TIMER1_COMPA_vect)
{
#ifdef BENCH_ISR_PIN
    PORTC |= 1 << 5;
#endif
    uint8_t t0 = TCNT0;
    uint8_t port = PORTD & ~STEP_MASK;
    PORTD = (uint8_t)(port | (pending_steps ^ step_invert));
    uint8_t new_dir = 0;
    if (seg_left == 0) {
        if (seg_head == seg_tail) { /* nothing left: stop after this pulse */
            TCCR1B = 1 << WGM12;
            TIMSK1 = 0;
            running = 0;
            while ((uint8_t)(TCNT0 - t0) < pulse_ticks) {
            }
            PORTD = (uint8_t)(port | step_invert);
            pending_steps = 0;
#ifdef BENCH_ISR_PIN
            PORTC &= ~(1 << 5);
#endif
            return;
        }
        segment_t *seg = &seg_ring[ring_slot(seg_tail, SEG_SIZE)];
        OCR1A = seg->period;
        seg_left = seg->events;
        if (seg->flags & SEG_FIRST) {
            blk = &step_blocks[seg->block];
            counter[0] = counter[1] = (int16_t)(blk->events >> 1);
            /* direction pin high: positive (the virtual plotter's convention; $3 inverts) */
            uint8_t d = 0;
            if (!(blk->dir_negative & 1))
                d |= 1 << X_DIR_BIT;
            if (!(blk->dir_negative & 2))
                d |= 1 << Y_DIR_BIT;
            new_dir = 1;
            dir_bits = d;
        }
    }
    uint8_t steps = 0;
    counter[0] -= blk->steps[0];
    if (counter[0] < 0) {
        counter[0] += blk->events;
        steps |= 1 << X_STEP_BIT;
        if (dir_bits & (1 << X_DIR_BIT))
            position[0]++;
        else
            position[0]--;
    }
    counter[1] -= blk->steps[1];
    if (counter[1] < 0) {
        counter[1] += blk->events;
        steps |= 1 << Y_STEP_BIT;
        if (dir_bits & (1 << Y_DIR_BIT))
            position[1]++;
        else
            position[1]--;
    }
    pending_steps = steps;
    if (--seg_left == 0)
        seg_tail++; /* segment consumed: its slot may be refilled */
    while ((uint8_t)(TCNT0 - t0) < pulse_ticks) {
    }
    port = PORTD & ~STEP_MASK;
    PORTD = (uint8_t)(port | step_invert);
    if (new_dir)
        PORTD = (uint8_t)((PORTD & ~DIR_MASK) | (dir_bits ^ dir_invert));
#ifdef BENCH_ISR_PIN
    PORTC &= ~(1 << 5);
#endif
}
