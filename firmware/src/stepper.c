#include <avr/interrupt.h>
#include <avr/io.h>
#include <util/atomic.h>
#include <util/delay.h>
#include "drive.h"
#include "ring.h"
#include "segment.h"
#include "settings.h"
#include "stepper.h"

static volatile uint8_t running;
static volatile int32_t position[N_AXIS];   /* motor steps */
static uint8_t pulse_ticks;                 /* Timer0 ticks (0.5 us) */
static uint8_t enabled;

/* state of the step interrupt */
static uint8_t pending_steps;   /* axes to step at the next tick (bit0 X, bit1 Y) */
static uint8_t dir_negative;    /* axes of the current block that move negative */
static uint16_t seg_left;
static step_block_t *blk;
static int16_t counter[N_AXIS]; /* Bresenham: 16-bit, blocks are at most PLAN_MAX_EVENTS */

void stepper_apply_settings(void)
{
    pulse_ticks = (uint8_t)(settings.pulse_us * 2 + 1); /* +1: the first tick may be partly gone */
    drive_apply_settings();
}

void stepper_init(void)
{
#ifdef BENCH_ISR_PIN
    IO_OUTPUT(BENCH_ISR);
#endif
    TCCR0A = 0;
    TCCR0B = 1 << CS01;          /* Timer0 free-running at 2 MHz: pulse-length clock */
    TCCR1A = 0;
    TCCR1B = 1 << WGM12;         /* CTC, clock off until a move starts */
    enabled = 0;
    drive_init();
    stepper_apply_settings();
}

void stepper_enable(uint8_t on)
{
    enabled = on;
    drive_enable(on);
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
        drive_step_end();
        was = running;
        running = 0;
        /* steps counted but never pulsed: take them back so the position stays true */
        for (uint8_t a = 0; a < N_AXIS; a++)
            if (pending_steps & (1 << a))
                position[a] += (dir_negative & (1 << a)) ? 1 : -1;
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
    for (uint8_t a = 0; a < N_AXIS; a++)
        if (mask & (1 << a))
            position[a] += (dir_negative & (1 << a)) ? -1 : 1;
    drive_set_dir(dir_negative);
    _delay_us(2); /* direction setup time before the edge */
    drive_step(mask);
#if DRIVE_PULSED
    _delay_us(10);
    drive_step_end();
#endif
}

/* One step event per tick: emit the pulse computed last tick (so its edge
 * has no jitter from the work below), then run Bresenham for the next one.
 * Directions change only after the pulse falls, a full period before the
 * next edge. */
ISR(TIMER1_COMPA_vect)
{
#ifdef BENCH_ISR_PIN
    IO_HIGH(BENCH_ISR);
#endif
    uint8_t t0 = TCNT0;
    drive_step(pending_steps);
    uint8_t new_dir = 0;
    if (seg_left == 0) {
        if (seg_head == seg_tail) { /* nothing left: stop after this pulse */
            TCCR1B = 1 << WGM12;
            TIMSK1 = 0;
            running = 0;
#if DRIVE_PULSED
            while ((uint8_t)(TCNT0 - t0) < pulse_ticks) {
            }
            drive_step_end();
#endif
            pending_steps = 0;
#ifdef BENCH_ISR_PIN
            IO_LOW(BENCH_ISR);
#endif
            return;
        }
        segment_t *seg = &seg_ring[ring_slot(seg_tail, SEG_SIZE)];
        OCR1A = seg->period;
        seg_left = seg->events;
        if (seg->flags & SEG_FIRST) {
            blk = &step_blocks[seg->block];
            counter[0] = counter[1] = (int16_t)(blk->events >> 1);
            new_dir = 1;
            dir_negative = blk->dir_negative;
        }
    }
    uint8_t steps = 0;
    counter[0] -= blk->steps[0];
    if (counter[0] < 0) {
        counter[0] += blk->events;
        steps |= 1;
        if (dir_negative & 1)
            position[0]--;
        else
            position[0]++;
    }
    counter[1] -= blk->steps[1];
    if (counter[1] < 0) {
        counter[1] += blk->events;
        steps |= 2;
        if (dir_negative & 2)
            position[1]--;
        else
            position[1]++;
    }
    pending_steps = steps;
    if (--seg_left == 0)
        seg_tail++; /* segment consumed: its slot may be refilled */
#if DRIVE_PULSED
    while ((uint8_t)(TCNT0 - t0) < pulse_ticks) {
    }
    drive_step_end();
#endif
    if (new_dir)
        drive_set_dir(dir_negative);
#ifdef BENCH_ISR_PIN
    IO_LOW(BENCH_ISR);
#endif
}
