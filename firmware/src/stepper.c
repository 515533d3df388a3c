#include <avr/interrupt.h>
#include <avr/io.h>
#include <stddef.h>
#include <util/atomic.h>
#include <util/delay.h>
#include "drive.h"
#include "ring.h"
#include "segment.h"
#include "settings.h"
#include "step_tick.h"
#include "stepper.h"

/* Running: Timer1's compare interrupt is on (it is only ever on while the
 * steppers run; no RAM for a flag). */
#define RUNNING() TIMSK1 /* nonzero: running */
/* Motor position: no step is counted as it is made. tick.position holds
 * where the motors are at the end of the block under way (the tick adds a
 * block's steps when it loads the block's first segment); the steps it has
 * still to make follow from its Bresenham state (block_left_to_step), for
 * the few readers of the position. */
static uint8_t enabled;

#if STEP_TICK_ASM
/* step_tick.S takes these from segment.h's and stepper.c's C layout */
_Static_assert(offsetof(segment_t, events) == SEG_EVENTS_AT, "segment_t.events");
_Static_assert(offsetof(segment_t, period) == SEG_PERIOD_AT, "segment_t.period");
_Static_assert(offsetof(segment_t, block) == SEG_BLOCK_AT, "segment_t.block");
_Static_assert(offsetof(segment_t, flags) == SEG_FLAGS_AT, "segment_t.flags");
_Static_assert(sizeof(segment_t) == 7, "segment_t: step_tick.S multiplies by 7");
_Static_assert(SEG_FIRST == 1 << SEG_FIRST_BIT, "SEG_FIRST");
_Static_assert(offsetof(step_block_t, steps) == BLK_STEPS_AT, "step_block_t.steps");
_Static_assert(offsetof(step_block_t, events) == BLK_EVENTS_AT, "step_block_t.events");
_Static_assert(offsetof(step_block_t, dir_negative) == BLK_DIR_AT, "step_block_t.dir_negative");
_Static_assert(offsetof(tick_state_t, position) == TICK_POSITION_AT, "tick.position");
_Static_assert(offsetof(tick_state_t, counter) == TICK_COUNTER_AT, "tick.counter");
_Static_assert(offsetof(tick_state_t, steps) == TICK_STEPS_AT, "tick.steps");
_Static_assert(offsetof(tick_state_t, events) == TICK_EVENTS_AT, "tick.events");
_Static_assert(offsetof(tick_state_t, k) == TICK_K_AT, "tick.k");
_Static_assert(offsetof(tick_state_t, left) == TICK_LEFT_AT, "tick.left");
#endif

/* state of the step interrupt */
/* in general purpose I/O registers: read or written in one cycle instead of
 * two, and GPIOR0's bits set in place (sbi: the tick sets each axis's step
 * bit as it finds it, no register held across both axes) */
#define PENDING_STEPS GPIOR0    /* DRIVE_X / DRIVE_Y bits to step at the next tick */
#define DIR_NEGATIVE GPIOR1     /* axes of the current block that move negative */
/* the rest of the tick's state: step_tick.h (step_tick.S reads it by name) */
tick_state_t tick;
#if STEP_TICK_ASM
uint8_t tick_dir_invert;
#endif

void stepper_apply_settings(void)
{
    /* +1: the first tick after the count is reset may be partly gone */
    OCR0A = (uint8_t)(settings.pulse_us * 2 + 1); /* Timer0 ticks (0.5 us) */
#if STEP_TICK_ASM
    tick_dir_invert = settings.dir_invert;
#endif
    drive_apply_settings();
}

void stepper_init(void)
{
#ifdef BENCH_ISR_PIN
    IO_OUTPUT(BENCH_ISR);
#ifdef BENCH_ISR_END
    IO_OUTPUT(BENCH_ISR_END);
#endif
#endif
    TCCR0A = 0;
    TCCR0B = 1 << CS01;          /* Timer0 free-running at 2 MHz: its compare A ends step pulses */
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
uint8_t stepper_busy(void) { return RUNNING(); }

/* Where an axis's motor is: the end of the block under way less the steps
 * it has still to make. From counter = events/2 - k * steps + made * events
 * (each step adds events back), `made` divides out exactly; the dividend
 * is never negative, so unsigned arithmetic (wrapping on the way) does.
 * The state is read with interrupts shut (a few loads: a due step tick
 * waits no longer than that), the division (~600 cycles) runs with them
 * on; the axes may be a tick apart while the steppers run. */
static __attribute__((noinline)) int32_t motor_at(uint8_t a)
{
    int32_t position;
    uint16_t counter, steps, events, k;
    uint8_t negative;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        position = tick.position[a];
        counter = (uint16_t)tick.counter[a];
        steps = (uint16_t)tick.steps[a];
        events = (uint16_t)tick.events;
        k = (uint16_t)(tick.k - tick.left);
        negative = DIR_NEGATIVE;
    }
    uint16_t made = 0;
    if (k) /* (no block yet: events 0) */
        made = (uint16_t)(((uint32_t)k * steps + counter - (uint16_t)((int16_t)events >> 1)) / events);
    int16_t left = (int16_t)(steps - made);
    return position - ((negative >> a) & 1 ? -left : left);
}

/* No block under way (stopped): its steps are all made or forgotten. */
static void forget_block(void)
{
    tick.steps[0] = tick.steps[1] = 0;
    tick.k = tick.left = 0;
}

void stepper_start(void)
{
    if (RUNNING())
        return;
    if (seg_head == seg_tail) {
#if DRIVE_PULSED
        /* stopped and the last pulse ended: Timer0's interrupt off (it
         * would come at every 128 us wrap of the count) */
        if (!drive_pulsing)
            TIMSK0 = 0;
#endif
        return;
    }
    if (!enabled)
        stepper_enable(1);
    /* a block stopped part way (a hold, a halt) that the ring does not go
     * on with (its rest dropped, or everything flushed) is forgotten: the
     * position is where the motors stand; one it goes on with keeps its
     * events made (k - left). (Stopped: no tick changes the state.) */
    if ((seg_ring[ring_slot(seg_tail, SEG_SIZE)].flags & SEG_FIRST) &&
        (uint16_t)(tick.k - tick.left) != (uint16_t)tick.events) {
        for (uint8_t a = 0; a < N_AXIS; a++)
            tick.position[a] = motor_at(a);
        forget_block();
    }
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        PENDING_STEPS = 0;
        tick.k -= tick.left;
        tick.left = 0;
        /* simavr never fires a CTC timer whose compare value is 0: load one first */
        OCR1A = 100;
        TCNT1 = 0;
        TIFR1 = 1 << OCF1A;
        TIMSK1 = 1 << OCIE1A;
        TCCR1B = (1 << WGM12) | (1 << CS11);
#if DRIVE_PULSED
        /* the pulse-end interrupt stays on for the whole run rather than
         * being switched on by each tick and off by itself (~150 cycles a
         * 0.5 mm line); a compare with no pulse up (at the count's wrap,
         * on ticks slower than 128 us) ends nothing */
        TIFR0 = 1 << OCF0A;
        TIMSK0 = 1 << OCIE0A;
#endif
    }
}

uint8_t stepper_halt(void)
{
    uint8_t was;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        was = RUNNING() != 0;
        TCCR1B = 1 << WGM12;
        TIMSK1 = 0;
        TIMSK0 = 0;
        drive_step_end();
        /* steps computed but never pulsed: take them back so the position
         * stays true (the Bresenham state counts them as made) */
        if (PENDING_STEPS & DRIVE_X)
            tick.position[0] += (DIR_NEGATIVE & 1) ? 1 : -1;
        if (PENDING_STEPS & DRIVE_Y)
            tick.position[1] += (DIR_NEGATIVE & 2) ? 1 : -1;
        PENDING_STEPS = 0;
    }
    return was;
}

void stepper_get_position(int32_t *motor)
{
    for (uint8_t a = 0; a < N_AXIS; a++)
        motor[a] = motor_at(a);
}

void stepper_set_position(const int32_t *motor)
{
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        for (uint8_t a = 0; a < N_AXIS; a++)
            tick.position[a] = motor[a];
        forget_block();
    }
}

void stepper_pulse(uint8_t mask, uint8_t dir_negative)
{
    for (uint8_t a = 0; a < N_AXIS; a++)
        if (mask & (1 << a))
            tick.position[a] += (dir_negative & (1 << a)) ? -1 : 1; /* (stopped: no tick) */
    drive_set_dir(dir_negative);
    _delay_us(2); /* direction setup time before the edge */
    drive_step((uint8_t)((mask & 1 ? DRIVE_X : 0) | (mask & 2 ? DRIVE_Y : 0)));
#if DRIVE_PULSED
    _delay_us(10);
    drive_step_end();
#endif
}

#if !STEP_TICK_ASM
/* (the boards step_tick.h names run the tick in step_tick.S) */

/* The tick found its segment done (interrupts off): the next segment's
 * period and, for a block's first, its Bresenham terms, directions and
 * steps (into the position: where the block ends); or, the ring empty,
 * the stop (Timer0 still ends the pulse just raised). Returns the
 * segment's events (at least 1), 0 when stopped. */
static inline __attribute__((always_inline)) uint16_t tick_load(void)
{
    if (seg_head == seg_tail) {
        TCCR1B = 1 << WGM12;
        TIMSK1 = 0;
        PENDING_STEPS = 0;
        return 0;
    }
    const segment_t *seg = &seg_ring[ring_slot(seg_tail, SEG_SIZE)];
    OCR1A = seg->period;
    uint16_t events = seg->events;
    if (seg->flags & SEG_FIRST) {
        const step_block_t *b = seg->block;
        int16_t block_events = b->events;
        tick.events = block_events;
        tick.counter[0] = tick.counter[1] = (int16_t)(block_events >> 1);
        uint8_t negative = b->dir_negative;
        DIR_NEGATIVE = negative;
        drive_set_dir(negative);
        for (uint8_t a = 0; a < N_AXIS; a++) {
            int16_t st = b->steps[a];
            tick.steps[a] = st;
            tick.position[a] += (negative >> a) & 1 ? -st : st;
        }
        tick.k = events;
    } else {
        tick.k += events;
    }
    return events;
}

/* Timer1 runs in CTC mode at 2 MHz: compare A (OCR1A, the segment's
 * period) is the step tick. Timer0 runs at 2 MHz and is reset to 0 at
 * the rising edge; its compare A (OCR0A = $0 in ticks) ends the pulse, so
 * neither interrupt waits. (A second compare on Timer1, or OCR0A moved
 * along a free-running count, would do on the chip, but simavr loses
 * Timer1's tick when OCR1B is rewritten at high rates, and a compare
 * value that wraps past 255.)
 *
 * One step event per tick: emit the pulse computed last tick (so its edge
 * has no jitter from the work below), then run Bresenham for the next one.
 * A new block's directions are written in the tick that computes its first
 * step: a whole period before that step's edge, and after the edge of the
 * old block's last step made at the top of the tick (past its hold time).
 *
 * The C tick, for the boards that do not run step_tick.S (step_tick.h).
 * Cycle budget, measured by bench/firmware_bench.py at 50 kHz on both axes
 * (a period of 320 cycles) when uno-cnc-shield and mega-ramps14 still ran
 * it, entry and exit included: on the 328P 179 cycles
 * on average (117 body + 62 entry/exit as the bench counts them: the
 * prologue and epilogue save 6 registers, ~50 cycles with the response and
 * reti; the bench also counts the body's in/out on r1x), 269 at worst on the
 * tick that loads a segment starting a block; on the 2560 187 and 277 (its
 * 3-byte return address: 70 entry/exit). Was 213/290 and 215/294. The
 * busiest period holds a worst tick alone: a tick that outlasts the pulse
 * ends it itself, so the pulse-end interrupt below (21 cycles worst) runs
 * only after short ticks. Per 0.5 mm line of the bench's CPU-bound run
 * (about 36 ticks) 5,431 cycles (was 6,941), then with a count per step
 * (since dropped: a block's steps go into the position when it starts, a
 * 32-bit add once a block). Nothing here calls a function (a call would
 * make the compiler save every call-clobbered register on each tick).
 * Nothing else may hold a due tick up for long (a late edge is a short step
 * period for the driver): see servo.c's and serial_rx.S's interrupts. */
ISR(TIMER1_COMPA_vect)
{
#ifdef BENCH_ISR_PIN
    IO_HIGH(BENCH_ISR);
#endif
#if DRIVE_PULSED
    /* a pulse still up (its end came late: never at the planned rates) falls
     * first, keeping edges paired (on a shared port with none up this
     * writes 0: no toggle, and no test) */
    if (DRIVE_ONE_PORT || drive_pulsing)
        drive_step_end();
    drive_step(PENDING_STEPS);
    TCNT0 = 0; /* compare A (OCR0A = $0) ends the pulse */
    TIFR0 = 1 << OCF0A; /* (one that came before the reset: not this pulse's end) */
#else
    drive_step(PENDING_STEPS);
#endif
    uint16_t left = tick.left;
    if (left == 0) {
        left = tick_load();
        if (left == 0) {
#ifdef BENCH_ISR_PIN
            IO_LOW(BENCH_ISR);
#endif
            return;
        }
    }
    /* the segment's last event: its slot may be refilled (all of it is
     * copied above) */
    if (--left == 0)
        seg_tail++;
    tick.left = left;
    /* each step bit set where it is found: fewer registers held; no step
     * is counted (the position follows from this state: motor_at) */
    int16_t c = tick.counter[0] - tick.steps[0];
    if (c < 0) {
        c += tick.events;
        PENDING_STEPS = DRIVE_X;
    } else {
        PENDING_STEPS = 0;
    }
    tick.counter[0] = c;
    c = tick.counter[1] - tick.steps[1];
    if (c < 0) {
        c += tick.events;
        PENDING_STEPS |= DRIVE_Y;
    }
    tick.counter[1] = c;
#if DRIVE_PULSED
    if (TIFR0 & (1 << OCF0A)) {
        /* a long tick (a block starts) outlasted the pulse: end it now rather
         * than after the next tick's interrupt, which outranks Timer0's */
        drive_step_end();
        TIFR0 = 1 << OCF0A;
    }
#endif
#ifdef BENCH_ISR_PIN
    IO_LOW(BENCH_ISR);
#endif
}

#endif /* !STEP_TICK_ASM */

#if DRIVE_PULSED
#if DRIVE_ONE_PORT
/* The pulse ends $0 us after its edge: the pulsing bits written to the step
 * port's PIN register toggle back. Naked: nothing here changes SREG and it
 * needs one register (and no zero register: r1 may be mid-multiply when it
 * comes), so it saves only that one; the compiler's version also saved r0,
 * r1 and SREG. It runs after a tick shorter than the pulse (one or no axis
 * stepping); a longer tick ends the pulse itself. Cycle budget, measured by
 * bench/firmware_bench.py: 21 cycles worst, entry and exit included (was 39
 * to 50, then 23 while it switched itself off; 23 on the 2560). On for the
 * whole run (stepper_start): on ticks slower than Timer0's 128 us wrap it
 * also comes once a wrap with no pulse up, and writes 0 (no toggle).
 * The step port must be in I/O space (ports A-G), as both boards' are. */
ISR(TIMER0_COMPA_vect, ISR_NAKED)
{
    __asm__ volatile(
        "push r24\n\t"
#if defined(BENCH_ISR_PIN) && defined(BENCH_ISR_END)
        "sbi %[bench_port], %[bench_bit]\n\t"
#endif
        "in r24, %[pulsing]\n\t"
        "out %[pin], r24\n\t"
        "ldi r24, 0\n\t"
        "out %[pulsing], r24\n\t"
#if defined(BENCH_ISR_PIN) && defined(BENCH_ISR_END)
        "cbi %[bench_port], %[bench_bit]\n\t"
#endif
        "pop r24\n\t"
        "reti\n\t"
        :
        : [pulsing] "I"(_SFR_IO_ADDR(drive_pulsing)), [pin] "I"(_SFR_IO_ADDR(IO_PINREG(X_STEP)))
#if defined(BENCH_ISR_PIN) && defined(BENCH_ISR_END)
          , [bench_port] "I"(_SFR_IO_ADDR(IO_PORT(BENCH_ISR_END))), [bench_bit] "I"(IO_BIT(BENCH_ISR_END))
#endif
    );
}
#else
/* The pulse ends $0 us after its edge. Cycle budget: about 50 cycles,
 * entry and exit included (step pins on two ports: two toggles). */
ISR(TIMER0_COMPA_vect)
{
    drive_step_end();
}
#endif
#endif
