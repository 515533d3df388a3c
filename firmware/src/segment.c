#include <math.h>
#include "planner.h"
#include "ring.h"
#include "segment.h"

segment_t seg_ring[SEG_SIZE];
step_block_t step_blocks[SEG_SIZE];
volatile uint8_t seg_head, seg_tail;

/* the preparer's wait (prep_room); 4 blocks by measurement: the CPU-bound
 * bench line rate on uno-cnc-shield was 696 at 8, 700.0 at 4, 699.9 at 3 */
#ifndef PREP_WAIT_BLOCKS
#define PREP_WAIT_BLOCKS 4
#endif
#ifndef PREP_WAIT_SEGMENTS
#define PREP_WAIT_SEGMENTS 2
#endif
#ifndef PREP_WAIT_SHORT
#define PREP_WAIT_SHORT 4
#endif
#ifndef PREP_WAIT_TICKS
#define PREP_WAIT_TICKS (STEP_TIMER_HZ / 250) /* 4 ms */
#endif
static struct prep_state {
    uint8_t active;      /* preparing plan_current() */
    uint8_t block;       /* its step_blocks index */
    uint8_t hold, stopped;
    uint16_t done;       /* events prepared (0: the next segment is the block's first) */
    uint16_t events;     /* the block's step events */
    float s;             /* mm prepared */
    float v;             /* speed at s, mm/s */
    plan_motion_t m;     /* the block's length and acceleration */
#if PLAN_CACHE_MOTION
    float ve, ve2;       /* the last block's exit and its square (RAM to spare: a multiply a block less) */
#endif
} prep;

/* The preparer's state through a pointer the compiler cannot fold back into
 * absolute addresses: its float fields are then read and written with
 * displacements (2-byte instructions) instead of lds/sts (4 bytes each),
 * ~400 B less flash for the same work. */
static inline struct prep_state *prep_at(void)
{
    struct prep_state *p = &prep;
    __asm__("" : "+r"(p));
    return p;
}

void seg_reset(void)
{
    seg_head = seg_tail = 0;
    prep.active = prep.hold = prep.stopped = 0;
    prep.v = 0.0f;
}

void seg_hold(uint8_t on)
{
    prep.hold = on;
    if (!on)
        prep.stopped = 0;
}

uint8_t seg_hold_reached(void) { return prep.hold && prep.stopped; }
float seg_speed(void) { return prep.v; }

plan_line_t seg_exec_line(void)
{
    uint8_t tail = seg_tail; /* the step interrupt only moves it forward; its slot stays valid */
    if (tail != seg_head)
        return seg_ring[ring_slot(tail, SEG_SIZE)].block->line;
    const plan_block_t *b = plan_current();
    return b ? b->line : 0;
}

void seg_drop_block(void)
{
    if (prep.active)
        plan_discard_current();
    prep.active = 0;
    prep.v = 0.0f;
}

/* x / 2 for x >= 0: one off its exponent (a multiply is ~130 cycles here);
 * below 2^-125 (no speed^2 this code meets) x itself */
static float half(float x)
{
    int32_t bits;
    memcpy(&bits, &x, sizeof(bits));
    if (bits >= 0x01000000L) /* a normal number that stays one */
        bits -= 1L << 23;
    memcpy(&x, &bits, sizeof(x));
    return x;
}

/* Advance (s, v) along the block for up to dt seconds. The profile is
 * rebuilt from the present state each time: accelerate toward the cruise
 * speed, cruise, decelerate to the exit speed, so a planner that raised
 * the exit speed meanwhile is followed at once. Returns the time used
 * (less than dt when the block or a hold ends first). */
static float advance(struct prep_state *p, const plan_block_t *b, float dt)
{
    int32_t s_bits; /* 0: at the block's start */
    memcpy(&s_bits, &p->s, sizeof(s_bits));
    float remaining = s_bits ? p->m.mm - p->s : p->m.mm;
    float v = p->v;
    if (p->hold) {
        plan_motion_complete(b, &p->m);
        float a = p->m.accel;
        float t_stop = v * p->m.inv_accel;
        float d_stop = 0.5f * v * t_stop;
        float tt = dt < t_stop ? dt : t_stop;
        float ds = v * tt - 0.5f * a * tt * tt;
        if (ds >= remaining) { /* block ends before the stop: time to cover the rest */
            float vend2 = v * v - 2.0f * a * remaining;
            float vend = vend2 > 0.0f ? sqrtf(vend2) : 0.0f;
            p->s = p->m.mm;
            p->v = vend;
            return (v - vend) * p->m.inv_accel;
        }
        p->s += ds;
        p->v = v - a * tt;
        if (tt >= t_stop || d_stop <= ds) {
            p->v = 0.0f;
            p->stopped = 1;
        }
        return tt;
    }
    float ve2 = plan_next_entry_sqr();
    float vn2 = plan_f16_to_float(b->nominal_sqr); /* read each time: overrides change it */
#if PLAN_CACHE_MOTION
    float v2 = float_same(v, p->ve) ? p->ve2 : v * v;
#else
    float v2 = v * v;
#endif
    if (plan_lt(vn2, v2) && plan_lt(vn2 * 1.0001f, v2)) { /* (the first test spares the multiply) */
        /* above the cruise speed (a feed override lowered it): slow down to
         * it first, where the block leaves room; otherwise the profile below
         * decelerates to the exit */
        plan_motion_complete(b, &p->m);
        float a = p->m.accel;
        float tn = (v - sqrtf(vn2)) * p->m.inv_accel;
        float tt = plan_lt(dt, tn) ? dt : tn;
        float ds = v * tt - 0.5f * a * tt * tt;
        if (plan_lt(ds, remaining)) {
            p->s += ds;
            p->v = v - a * tt;
            return tt;
        }
    }
    if (plan_lt(vn2, v2))
        vn2 = v2; /* still above it where the block ends: on at v, down to the exit at the end */
    if (plan_lt(vn2, ve2))
        ve2 = vn2;
    /* r2: the speed^2 the rest of the block gains or loses at most, 2 a
     * times what remains. At the block's start its accel_dist2 (what the
     * planner counted on) and 1 / a from it: on the 328P one division, no
     * events per mm nor axis limits (plan_motion_complete) for a block that
     * ends within dt */
    float r2, inv_a;
    if (!s_bits) {
        r2 = plan_sqr_to_float(b->accel_dist2);
#if PLAN_CACHE_MOTION
        inv_a = p->m.inv_accel;
#else
        inv_a = (remaining + remaining) / r2;
#endif
    } else {
        plan_motion_complete(b, &p->m);
        r2 = 2.0f * p->m.accel * remaining;
        inv_a = p->m.inv_accel;
    }
    /* the profile in closed form: accelerate to vp, cruise there (a * its
     * time: the speed^2 beyond vn^2 the peak would have reached, over vp),
     * decelerate to ve. The peak is below v^2 or ve^2 when the exit is out
     * of reach (|v^2 - ve^2| > r2): then the nearest one it can reach. */
    float peak2 = half(v2 + ve2 + r2), cruise = 0.0f, vp = v;
    if (plan_lt(peak2, v2)) {
        ve2 = v2 - r2;
        peak2 = v2;
    } else if (plan_lt(peak2, ve2)) {
        ve2 = v2 + r2;
        peak2 = ve2;
    }
    if (plan_lt(vn2, peak2)) {
        vp = sqrtf(vn2);
        cruise = (peak2 - vn2) / vp;
    } else if (plan_lt(v2, peak2)) {
        vp = sqrtf(peak2);
    }
    float ve = sqrtf(ve2);
    float t = vp - v + (vp - ve);
    if (plan_lt(0.0f, cruise))
        t += cruise;
    t *= inv_a;
    if (!plan_lt(dt, t)) {
        /* the block ends within dt (the short lines of a fast stream: their
         * whole block in one step, no phase walked) */
        p->s = p->m.mm;
        p->v = ve;
#if PLAN_CACHE_MOTION
        p->ve = ve;
        p->ve2 = ve2;
#endif
        return t;
    }
    /* it goes on past dt: where dt ends the acceleration, the cruise or the
     * deceleration */
    plan_motion_complete(b, &p->m);
    float a = p->m.accel;
    inv_a = p->m.inv_accel;
    float ta = (vp - v) * inv_a, tc = cruise * inv_a;
    if (plan_lt(dt, ta)) {
        p->s += v * dt + 0.5f * a * dt * dt;
        p->v = v + a * dt;
        return dt;
    }
    float s = 0.5f * (v + vp) * ta;
    dt -= ta;
    if (plan_lt(dt, tc)) {
        p->s += s + vp * dt;
        p->v = vp;
        return dt + ta;
    }
    float td = dt - tc;
    p->s += s + vp * dt - 0.5f * a * td * td;
    p->v = vp - a * td;
    return dt + ta;
}

static void start_block(struct prep_state *p, const plan_block_t *b)
{
    p->block = (uint8_t)((p->block + 1) & (SEG_SIZE - 1));
    step_block_t *sb = &step_blocks[p->block];
    p->events = plan_events(b);
    sb->events = (int16_t)p->events;
    sb->dir_negative = 0;
    sb->line = b->line;
    for (uint8_t a = 0; a < N_AXIS; a++) {
        int16_t st = b->steps[a]; /* |st| <= PLAN_MAX_EVENTS: -st fits */
        sb->steps[a] = (int16_t)(st < 0 ? -st : st);
        if (st < 0)
            sb->dir_negative |= (uint8_t)(1 << a);
    }
    p->active = 1;
    p->s = 0.0f;
    p->done = 0;
    plan_block_motion(b, &p->m);
}

/* Step-timer ticks per event for n events in `time` seconds, rounded, within
 * the timer's range: one division per segment, in integers (the segment's
 * ticks, 16 bits unless it is over 32 ms: ~200 cycles, where a float
 * division is ~550). */
static uint16_t event_period(float time, uint16_t n)
{
    float ticks = time * (float)STEP_TIMER_HZ; /* (rounded with the division's n / 2) */
    uint32_t total = plan_lt(ticks, 4.0e9f) ? (uint32_t)ticks : 4000000000UL; /* (and NaN) */
    total += n >> 1;
    uint32_t period = total <= 0xFFFFu ? (uint16_t)total / n : total / n;
    if (period < STEP_PERIOD_MIN)
        period = STEP_PERIOD_MIN;
    return period > 0xFFFFu ? 0xFFFFu : (uint16_t)period;
}

/* Room for another segment: one slot fewer than the ring, so a step block
 * is never reused while a queued segment still points at it. With few
 * blocks queued (PREP_WAIT_BLOCKS: the last of them planned down to a stop
 * near its end; every planner holds more, so it is open to more lines) and
 * a segment of at least PREP_WAIT_TICKS queued beyond the one under way,
 * none (and at most PREP_WAIT_SHORT segments while they are shorter): a
 * segment prepared later sees the lines that came meanwhile (a stream's
 * start stopped after each of its first blocks), and the one queued covers
 * any main-loop pass meanwhile. Inline: fill's loop is its one caller. */
static inline __attribute__((always_inline)) uint8_t prep_room(const struct prep_state *p)
{
    uint8_t tail = seg_tail; /* once: the step interrupt moves it (then "next" is under way) */
    uint8_t n = ring_count(seg_head, tail);
    if (n >= SEG_SIZE - 1)
        return 0;
    if (n < PREP_WAIT_SEGMENTS || p->hold || plan_count() > PREP_WAIT_BLOCKS)
        return 1;
    const segment_t *next = &seg_ring[ring_slot((uint8_t)(tail + 1), SEG_SIZE)];
    return n < PREP_WAIT_SHORT && (uint32_t)next->events * (next->period + 1u) < PREP_WAIT_TICKS;
}

/* seg_fill once there is a block and room (its register saves are not for
 * every idle main-loop pass) */
static __attribute__((noinline)) uint8_t fill(struct prep_state *const p)
{
    uint8_t added = 0;
    for (;;) {
        if (p->hold && p->stopped)
            break;
        plan_block_t *b = plan_current();
        if (!b) {
            p->v = 0.0f;
            break;
        }
        if (!prep_room(p))
            break;
        if (!p->active)
            start_block(p, b);
        float time = 0.0f;
        uint32_t target;
        uint8_t ended;
        uint8_t rounds = 0;
        do {
            float t = advance(p, b, SEGMENT_S);
            time = rounds ? time + t : t;
            ended = !plan_lt(p->s, p->m.mm);
            target = p->events;
            if (!ended) { /* a step is due half way */
                plan_motion_complete(b, &p->m);
                uint32_t e = (uint32_t)(p->s * p->m.events_per_mm + 0.5f);
                if (e < target)
                    target = e;
            }
        } while (target == p->done && !ended && !(p->hold && p->stopped) && ++rounds < 8);
        if (target == p->done && !ended && !(p->hold && p->stopped))
            target = p->done + 1; /* slower than the timer can time: one step anyway */
        if (!ended && plan_lt(0.0f, p->v)) {
            /* end the segment exactly on its last step, so its rate is exact;
             * the distance to that step is moved over to the next segment */
            float epm = p->m.events_per_mm;
            float back = (p->s * epm - (float)target) / (epm * p->v); /* seconds past the step */
            if (plan_lt(fabsf(back), 0.25f * time)) { /* when slow, v is too rough an estimate */
                time -= back;
                p->s -= back * p->v;
            }
        }
        if (target - p->done > 60000u) { /* absurd rates: keep a segment within 16 bits */
            target = p->done + 60000u;
            ended = 0;
        }
        uint32_t n = target - p->done;
        if (n > 0) {
            segment_t *seg = &seg_ring[ring_slot(seg_head, SEG_SIZE)];
            seg->events = (uint16_t)n;
            seg->period = (uint16_t)(event_period(time, (uint16_t)n) - 1); /* CTC: OCR1A + 1 ticks */
            seg->block = &step_blocks[p->block];
            seg->flags = p->done ? 0 : SEG_FIRST;
            p->done = (uint16_t)target;
            seg_head++; /* publish after the segment is complete */
            added = 1;
        }
        if (target >= p->events) {
            plan_discard_current();
            p->active = 0;
        } else {
            plan_motion_complete(b, &p->m);
            plan_set_exec_exit_limit(p->v * p->v + 2.0f * p->m.accel * (p->m.mm - p->s));
        }
    }
    return added;
}

uint8_t seg_fill(void)
{
    if (!plan_current()) {
        prep.v = 0.0f;
        return 0;
    }
    if (ring_count(seg_head, seg_tail) >= SEG_SIZE - 1)
        return 0; /* (fill's register saves for nothing) */
    return fill(prep_at());
}
