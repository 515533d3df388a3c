#include <math.h>
#include <stddef.h>
#include <string.h>
#include "planner.h"
#include "settings.h"

#define STRAIGHT_COS -0.999999f
#define REVERSAL_COS 0.999999f
#define MIN_STEP_RATE 32.0f /* steps/s the 2 MHz 16-bit step timer can time */

/* PLAN_SIZE - 1 usable blocks (the count tells full from empty, so no
 * slot is kept free) */
#define RING_SLOTS (PLAN_SIZE - 1)
static plan_block_t ring[RING_SLOTS];
#if PLAN_CACHE_MOTION
static plan_motion_t motion[RING_SLOTS]; /* ring[i]'s geometry, as geometry() gave it */
#endif
static uint8_t head, tail, count;
static int32_t position[N_AXIS];   /* cartesian steps where the last block ends */
/* the newest block's move in mm and its length (the next junction's corner;
 * its cruise speed is its nominal_sqr) */
static float prev_d[N_AXIS], prev_mm;
static plan_sqr_t exec_exit_limit; /* for ring[tail] */
static uint8_t feed_pct = 100, rapid_pct = 100; /* realtime overrides */
static float last_feed;        /* the last block's feed as given, and as stored in blocks */
static uint16_t last_feed_u16;
/* last_feed's cruise speed squared as set_nominal stores it, when no limit
 * can bind in any direction (0: one may): see plain_nominal */
static plan_f16_t feed_nominal;
/* an override change's recompute under way (plan_override_step) */
#define OV_SLICE 4
static uint8_t ov_at, ov_left;     /* next block to recompute, and how many to go */
static plan_f16_t ov_prev_nominal; /* the cruise speed^2 of the block before ov_at */
static plan_line_t line_number; /* for the blocks queued next */
/* The lazy backward pass (lazy_append): the newest lazy_n blocks (never the
 * oldest) hold in entry_sqr their entry minus lazy_add. Their entries are
 * the backward pass's sums (each the next one's plus its own accel_dist2,
 * the newest's its own), below their junction limits, with room to the
 * limit not growing toward the newest; a new block adds its accel_dist2 to
 * every one of them, i.e. to lazy_add. */
#if PLAN_LAZY
static uint8_t lazy_n;
static plan_sqr_t lazy_add;
#endif
void plan_set_line_number(plan_line_t n) { line_number = n; }

/* Reciprocals of the per-axis settings, so that plan_line multiplies where
 * it would divide (a float division costs ~500 cycles here); recomputed
 * after a setting they come from may have changed. Settings change only
 * with the planner empty (the firmware answers error:8 while blocks are
 * queued) and are followed by plan_settings_changed (a $ setting) or
 * plan_reset (a restore's reset, power-up, the host library's configure),
 * so only a block queued into an empty planner looks (a flag: no 24-byte
 * copy of the settings kept in RAM). */
static uint8_t axis_stale = 1;
static struct {
    float mm_per_step[N_AXIS];
    float s_per_mm[N_AXIS];       /* 1 / max rate in mm/s */
    float inv_accel[N_AXIS];
} axis;

void plan_settings_changed(void) { axis_stale = 1; }

static void refresh_axis(void)
{
    if (!axis_stale)
        return;
    axis_stale = 0;
    memset(&last_feed, 0xFF, sizeof(last_feed)); /* a NaN no F word gives: feed_nominal again */
    for (uint8_t a = 0; a < N_AXIS; a++) {
        axis.mm_per_step[a] = 1.0f / settings.steps_per_mm[a];
        axis.s_per_mm[a] = 60.0f / settings.max_rate[a];
        axis.inv_accel[a] = 1.0f / settings.accel[a];
    }
}


static uint8_t next_index(uint8_t i) { return (uint8_t)(i + 1 == RING_SLOTS ? 0 : i + 1); }
static uint8_t prev_index(uint8_t i) { return (uint8_t)(i == 0 ? RING_SLOTS - 1 : i - 1); }

void plan_reset(void)
{
    plan_settings_changed();
    head = tail = count = ov_left = 0;
#if PLAN_LAZY
    lazy_n = 0;
#endif
    exec_exit_limit = 0;
}

void plan_set_position(const int32_t *steps) { memcpy(position, steps, sizeof(position)); }
void plan_get_position(int32_t *steps) { memcpy(steps, position, sizeof(position)); }
uint8_t plan_free(void) { return (uint8_t)(PLAN_SIZE - 1 - count); }
uint8_t plan_count(void) { return count; }
plan_block_t *plan_current(void) { return count ? &ring[tail] : 0; }

uint16_t plan_events(const plan_block_t *b)
{
    uint16_t events = 0;
    for (uint8_t a = 0; a < N_AXIS; a++) {
        uint16_t m = (uint16_t)(b->steps[a] < 0 ? -b->steps[a] : b->steps[a]);
        if (m > events)
            events = m;
    }
    return events;
}

/* The scaling by PLAN_SQR_SCALE is an integer add to the float's exponent
 * field instead of a multiply (~150 cycles here), and the range checks are
 * integer compares of its bits. Exact for normal numbers; a subnormal one
 * comes out below 1 either way, i.e. 0. */
#define SQR_EXPONENT ((int32_t)PLAN_SQR_SHIFT << 23)
#define FLOAT_INF_BITS 0x7F800000L
#define SQR_MAX_BITS (0x4E800000L - SQR_EXPONENT) /* PLAN_SQR_MAX, 2^30, unscaled */
_Static_assert(PLAN_SQR_MAX == 1UL << 30, "SQR_MAX_BITS is 2^30's exponent");

plan_sqr_t plan_sqr_from_float(float v_sqr)
{
    int32_t bits;
    memcpy(&bits, &v_sqr, sizeof(bits));
    if (bits <= 0 || bits > FLOAT_INF_BITS) /* negative rounding leftovers (and NaN) are a stop */
        return 0;
    if (bits >= SQR_MAX_BITS)
        return PLAN_SQR_MAX;
    bits += SQR_EXPONENT;
    memcpy(&v_sqr, &bits, sizeof(v_sqr));
    return (plan_sqr_t)v_sqr;
}

/* v / 2^(exponent >> 23) */
static float sqr_to_float(plan_sqr_t v, int32_t exponent)
{
    float f = (float)v;
    if (v) { /* at least 1: a normal number */
        int32_t bits;
        memcpy(&bits, &f, sizeof(bits));
        bits -= exponent;
        memcpy(&f, &bits, sizeof(f));
    }
    return f;
}

float plan_sqr_to_float(plan_sqr_t v) { return sqr_to_float(v, SQR_EXPONENT); }

/* In 16-bit halves of the float's bits: the shifts are by one place, where
 * 32-bit shifts by 15 would be loops here. */
plan_f16_t plan_f16_from_float(float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof(bits));
    if ((int32_t)bits <= 0 || bits > FLOAT_INF_BITS) /* not above 0 (or NaN) */
        return 0;
    uint16_t hi = (uint16_t)(bits >> 16), lo = (uint16_t)bits;
    return (plan_f16_t)((uint16_t)(hi << 1) | ((lo & 0x8000u) ? 1u : 0u));
}

float plan_f16_to_float(plan_f16_t h)
{
    uint16_t hi = (uint16_t)(h >> 1), lo = (h & 1) ? 0x8000u : 0u;
    uint32_t bits = (uint32_t)hi << 16 | lo;
    float v;
    memcpy(&v, &bits, sizeof(v));
    return v;
}

#if PLAN_LAZY
plan_sqr_t plan_entry_sqr(const plan_block_t *b)
{
    int8_t back = (int8_t)(head - (uint8_t)(b - ring)); /* 1 for the newest */
    if (back <= 0)
        back += RING_SLOTS;
    return b->entry_sqr + ((uint8_t)back <= lazy_n ? lazy_add : 0);
}
#endif

float plan_next_entry_sqr(void)
{
    return count > 1 ? plan_sqr_to_float(plan_entry_sqr(&ring[next_index(tail)])) : 0.0f;
}

void plan_discard_current(void)
{
    if (!count)
        return;
    if (ov_left && ov_at == tail) { /* executed before the override walk got to it */
        ov_at = next_index(ov_at);
        ov_left--;
    }
    tail = next_index(tail);
    count--;
#if PLAN_LAZY
    if (lazy_n && lazy_n == count) { /* the new oldest was lazy: it is planned no more */
        ring[tail].entry_sqr += lazy_add;
        lazy_n--;
    }
#endif
    exec_exit_limit = count ? ring[tail].entry_sqr + ring[tail].accel_dist2 : 0;
}

void plan_set_exec_exit_limit(float v_sqr) { exec_exit_limit = plan_sqr_from_float(v_sqr); }

void plan_motor_steps(const int32_t *cart, int32_t *motor)
{
    if (settings.corexy) {
        motor[0] = cart[0] + cart[1];
        motor[1] = cart[0] - cart[1];
    } else {
        motor[0] = cart[0];
        motor[1] = cart[1];
    }
}

void plan_cart_from_motor(const int32_t *motor, int32_t *cart)
{
    if (settings.corexy) {
        /* A + B and A - B are always even for positions reached by
         * plan_motor_steps: halving is a shift (gcc's >> of a signed value
         * is arithmetic), no division's rounding toward zero */
        cart[0] = (motor[0] + motor[1]) >> 1;
        cart[1] = (motor[0] - motor[1]) >> 1;
    } else {
        cart[0] = motor[0];
        cart[1] = motor[1];
    }
}

/* Backward pass: every block must be able to slow to the next block's entry
 * (and the last to a stop). Forward pass: no block may enter faster than the
 * one before can accelerate to. Both on squared speeds: v^2 = u^2 + 2as.
 * The backward pass stops at a block that stays at its junction limit: the
 * blocks before it would get the values they already have, and the forward
 * pass resumes from there. A block the forward pass leaves as the backward
 * pass made it, below its junction limit, enters at the next one's entry
 * plus its own accel_dist2, so the next one is within its reach too: when
 * the backward pass left no block at its limit, the forward pass ends at
 * the first such block instead of walking the queue (a queue planned down
 * to a stop at its end, i.e. every look-ahead-bound one, has none: ~20
 * cycles a block). */
#if PLAN_LAZY
static plan_block_t *ring_prev(plan_block_t *b) { return b == ring ? &ring[RING_SLOTS - 1] : b - 1; }

/* Every lazy entry written out (before a full pass) */
static void materialize(void)
{
    plan_block_t *b = &ring[head];
    for (uint8_t n = lazy_n; n; n--) {
        b = ring_prev(b);
        b->entry_sqr += lazy_add;
    }
    lazy_n = 0;
}

/* The passes below with the new block b (at head, not yet counted) queued
 * behind the lazy blocks, where they would write no block but b and the
 * oldest lazy ones that reach their junction limits: 1 when done so (a few
 * compares, where the passes walk every lazy block), 0 to run them. The
 * block before the oldest lazy one is the executing one, or one at its
 * limit where the backward pass stops; the forward pass must not cap the
 * oldest lazy one (then it stops there too). */
static uint8_t lazy_append(plan_block_t *nb)
{
    plan_sqr_t add = nb->accel_dist2, sum = lazy_add + add;
    if (add >= nb->max_entry_sqr)
        return 0;
    plan_block_t *p = ring_prev(nb);
    if (lazy_n && (int32_t)(nb->max_entry_sqr - add) < (int32_t)(p->max_entry_sqr - (p->entry_sqr + sum)))
        return 0; /* the room to the limit would grow toward the oldest */
    int8_t i = (int8_t)(head - lazy_n);
    plan_block_t *b = &ring[i < 0 ? i + RING_SLOTS : i];
    p = ring_prev(b);
    for (;;) {
        plan_sqr_t e = b == nb ? add : b->entry_sqr + sum, v = b->max_entry_sqr, reach;
        uint8_t below = e < v;
        if (below)
            v = e;
        if (p == &ring[tail])
            reach = exec_exit_limit;
        else if (p->entry_sqr == p->max_entry_sqr && v + p->accel_dist2 >= p->max_entry_sqr)
            reach = p->entry_sqr + p->accel_dist2;
        else
            return 0;
        if (v > reach)
            return 0;
        if (below)
            break;
        b->entry_sqr = v; /* at its limit: planned for good */
        lazy_n--;
        p = b;
        b = b == &ring[RING_SLOTS - 1] ? ring : b + 1;
    }
    lazy_add = sum;
    nb->entry_sqr = add - sum;
    lazy_n++;
    return 1;
}

/* The newest blocks that qualify as lazy after the passes, from the newest
 * back: each entry the backward sum, below its limit, the room to the
 * limit not growing toward the oldest. */
static void lazy_rebuild(void)
{
    lazy_add = 0;
    plan_sqr_t sum = 0;
    int32_t room = INT32_MAX;
    plan_block_t *b = ring_prev(&ring[head]);
    for (uint8_t n = count; n > 1; n--) {
        sum += b->accel_dist2; /* below 2^31: the last sum was below a limit */
        int32_t r = (int32_t)(b->max_entry_sqr - sum);
        if (b->entry_sqr != sum || r <= 0 || r > room)
            break;
        room = r;
        lazy_n++;
        b = ring_prev(b);
    }
}
#else
static inline void materialize(void) {}
static inline uint8_t lazy_append(plan_block_t *nb)
{
    (void)nb;
    return 0;
}
static inline void lazy_rebuild(void) {}
#endif

static void recalculate(uint8_t full)
{
    /* pointers rather than ring indices: no index multiply per block */
    plan_block_t *const last = &ring[RING_SLOTS - 1];
    plan_block_t *const oldest = &ring[tail];
    plan_block_t *b = &ring[prev_index(head)];
    plan_block_t *first = oldest;
    plan_sqr_t next_entry = 0;
    uint8_t limited = 0; /* a block at its junction limit after first */
    for (uint8_t n = count; n > 1; n--) {
        plan_sqr_t e = next_entry + b->accel_dist2;
        if (e >= b->max_entry_sqr) {
            e = b->max_entry_sqr;
            if (e == b->entry_sqr && !full) {
                first = b;
                break;
            }
            limited = 1;
        }
        b->entry_sqr = e;
        next_entry = e;
        b = b == ring ? last : b - 1;
    }
    plan_sqr_t reach = first == oldest ? exec_exit_limit : first->entry_sqr + first->accel_dist2;
    plan_block_t *const end = &ring[head];
    for (b = first == last ? ring : first + 1; b != end; b = b == last ? ring : b + 1) {
        if (b->entry_sqr > reach)
            b->entry_sqr = reach;
        else if (!limited)
            break;
        reach = b->entry_sqr + b->accel_dist2; /* both <= PLAN_SQR_MAX: no overflow */
    }
    lazy_rebuild();
}

/* Cruise speed of a block: the programmed feed (in mm/s) or, for a rapid,
 * the axis limit, each scaled by its override (jogs keep theirs), within
 * the axis limits along the move (s_per_mm: the largest |u_axis| / max
 * rate), and no slower than the step timer can time. */
static float cruise_speed(float feed_mm_s, uint8_t flags, float s_per_mm, float events_per_mm)
{
    float speed;
    if (flags & PB_RAPID) {
        speed = 1.0f / s_per_mm;
        if (rapid_pct != 100)
            speed *= (float)rapid_pct * 0.01f;
    } else {
        speed = feed_mm_s;
        if (feed_pct != 100 && !(flags & PB_JOG))
            speed *= (float)feed_pct * 0.01f;
        if (plan_lt(1.0f, speed * s_per_mm))
            speed = 1.0f / s_per_mm;
    }
    if (plan_lt(speed * events_per_mm, MIN_STEP_RATE))
        speed = MIN_STEP_RATE / events_per_mm;
    return speed;
}

/* The tightest axis speed limit along a move: max over moving axes of
 * |u_axis| / max rate (s/mm), from the unit vector. */
static float axis_s_per_mm(const float *unit)
{
    float s_per_mm = 0.0f;
    for (uint8_t a = 0; a < N_AXIS; a++) {
        float u = fabsf(unit[a]);
        if (plan_lt(1.0e-6f, u)) {
            float r = u * axis.s_per_mm[a];
            if (plan_lt(s_per_mm, r))
                s_per_mm = r;
        }
    }
    return s_per_mm;
}

/* The rest of a block's motion once m->mm is known and m->inv_accel holds
 * the largest |d_mm| / accel (geometry): returns 1 / length. */
static float motion_finish(const plan_block_t *b, plan_motion_t *m)
{
    float inv_mm = 1.0f / m->mm;
    m->events_per_mm = (float)plan_events(b) * inv_mm;
    m->inv_accel *= inv_mm; /* some axis moves: x > 0 */
    return inv_mm;
}

/* Length, axis deltas in mm (into d_mm when given) and (in m->inv_accel)
 * the largest |d_mm| / accel; events per mm 0 (not yet: motion_finish, when
 * needed). The axis limits along the move: accel <= accel / |u| for every
 * moving axis; the tightest has the largest |u| / limit, i.e. the largest
 * |d_mm| / limit. Returns the length squared. */
static __attribute__((noinline)) float geometry(const plan_block_t *b, plan_motion_t *m, float *d_mm)
{
    int32_t motor[N_AXIS] = {b->steps[0], b->steps[1]}, cart[N_AXIS];
    float d[N_AXIS], mm2 = 0.0f, x = 0.0f;
    if (!d_mm)
        d_mm = d;
    plan_cart_from_motor(motor, cart);
    for (uint8_t a = 0; a < N_AXIS; a++) {
        d_mm[a] = (float)cart[a] * axis.mm_per_step[a];
        float sq = d_mm[a] * d_mm[a];
        mm2 = a ? mm2 + sq : sq; /* (0 + x is an add the compiler may not drop) */
        float r = fabsf(d_mm[a]) * axis.inv_accel[a];
        if (plan_lt(x, r))
            x = r;
    }
    m->mm = sqrtf(mm2);
    m->inv_accel = x;
    m->events_per_mm = 0.0f;
    return mm2;
}

/* The acceleration the segment preparer runs a block at: the one its
 * accel_dist2 (2 a mm, rounded down to 1/64 (mm/s)^2) stands for, so it
 * slows over the block by just what the planner counted on; a multiply
 * where 1 / inv_accel is a division (~550 cycles). Below 64 (mm/s)^2,
 * where the rounding could be more than 2^-12 of it, the division. */
static void run_accel(const plan_block_t *b, plan_motion_t *m, float inv_mm)
{
    if (b->accel_dist2 >= 4096)
        m->accel = sqr_to_float(b->accel_dist2, SQR_EXPONENT + (1L << 23)) * inv_mm; /* / 2 mm */
    else
        m->accel = 1.0f / m->inv_accel;
}

void plan_block_motion(const plan_block_t *b, plan_motion_t *m)
{
#if PLAN_CACHE_MOTION
    *m = motion[b - ring]; /* the axis settings cannot change while blocks are queued */
#else
    m->events_per_mm = 0.0f; /* not yet */
    m->inv_accel = 0.0f;
    if (!float_same(axis.mm_per_step[0], axis.mm_per_step[1])) {
        geometry(b, m, 0);
        return;
    }
    /* both axes at the same steps/mm (the usual machine): the square root of
     * the integer sum of squared steps (CoreXY: x^2 + y^2 = (A^2 + B^2) / 2),
     * two 16-bit multiplies where geometry converts and multiplies floats;
     * its axis limits when plan_motion_complete needs them (a block that
     * ends within one segment does not) */
    int32_t sq = (int32_t)b->steps[0] * b->steps[0] + (int32_t)b->steps[1] * b->steps[1];
    if (settings.corexy) /* (at most 2 * 30000^2: no overflow) */
        sq >>= 1;
    m->mm = sqrtf((float)sq) * axis.mm_per_step[0];
#endif
}

#if !PLAN_CACHE_MOTION
void plan_motion_complete(const plan_block_t *b, plan_motion_t *m)
{
    if (plan_lt(0.0f, m->events_per_mm))
        return;
    if (!plan_lt(0.0f, m->inv_accel))
        geometry(b, m, 0); /* the axis limits (and the length again, to within rounding) */
    run_accel(b, m, motion_finish(b, m));
}
#endif

/* A block's feed as stored (mm/min, rounded) in mm/s. */
static float feed_mm_s(uint16_t feed) { return (float)feed * (1.0f / 60.0f); }

/* The cruise speed squared, as set_nominal stores it, of every G1 block at
 * this speed (mm/s) without a feed override, when neither limit of
 * cruise_speed can bind whatever the direction (0 otherwise): at most 0.999
 * of every axis's max rate (an axis's share |u| <= 1, with room for the
 * float rounding of u) and at least 1.01 times the slowest step rate at
 * every axis's steps/mm over sqrt(2) (events per mm >= min steps/mm / sqrt 2
 * in any direction: the largest of two axes' steps, or CoreXY's |X| + |Y|,
 * is at least 1/sqrt(2) of the length in steps). The feed is modal: this
 * runs once per F change instead of five multiplies per line. */
static __attribute__((noinline)) plan_f16_t plain_nominal(float speed)
{
    for (uint8_t a = 0; a < N_AXIS; a++) {
        __asm__("" : "+r"(a)); /* (a loop: unrolled it was 100 B more) */
        if (!plan_lt(speed * axis.s_per_mm[a], 0.999f) ||
            plan_lt(speed * settings.steps_per_mm[a], MIN_STEP_RATE * 1.01f * 1.4143f))
            return 0;
    }
    return plan_f16_from_float(speed * speed);
}

/* The block's cruise speed squared as stored (16 bits, never above the
 * float one), from its feed, flags and direction (from the deltas d_mm,
 * with the motion finished here if it is not yet) with the overrides. A
 * block at a plain feed takes feed_nominal: no direction, no events per mm. */
static float set_nominal(plan_block_t *b, plan_motion_t *m, const float *d_mm)
{
    if (feed_nominal && b->feed == last_feed_u16 && !(b->flags & PB_RAPID) && feed_pct == 100) {
        b->nominal_sqr = feed_nominal;
    } else {
        float unit[N_AXIS];
        float inv_mm = plan_lt(0.0f, m->events_per_mm) ? 1.0f / m->mm : motion_finish(b, m);
        for (uint8_t a = 0; a < N_AXIS; a++)
            unit[a] = d_mm[a] * inv_mm;
        float speed = cruise_speed(feed_mm_s(b->feed), b->flags, axis_s_per_mm(unit), m->events_per_mm);
        b->nominal_sqr = plan_f16_from_float(speed * speed);
    }
    return plan_f16_to_float(b->nominal_sqr);
}

/* An override change recomputes every queued block (~5,000 cycles each:
 * the geometry and the cruise speed) in slices of OV_SLICE blocks, one per
 * plan_override_step, so that the main loop keeps the segment ring fed in
 * between (all 63 Mega blocks at once were ~20 ms, longer than 7 short
 * segments last). From the oldest block on: the executing one slows first.
 * Until the walk reaches the newest block, the others keep their old speeds
 * and junction limits, which were safe (a lowered cruise speed is honoured
 * by the segment preparer within the block). */
uint8_t plan_override_step(void)
{
    if (!ov_left)
        return 0;
    for (uint8_t n = OV_SLICE; n && ov_left; n--, ov_left--) {
        plan_block_t *b = &ring[ov_at];
        plan_motion_t m;
        float d[N_AXIS];
        geometry(b, &m, d);
        float nominal = set_nominal(b, &m, d);
        /* a junction is never faster than the cruise speeds on either side */
        if (ov_at != tail) {
            float before = plan_f16_to_float(ov_prev_nominal);
            plan_sqr_t c = plan_sqr_from_float(plan_lt(before, nominal) ? before : nominal);
            if (b->max_entry_sqr > c)
                b->max_entry_sqr = c;
        }
        ov_prev_nominal = b->nominal_sqr;
        ov_at = next_index(ov_at);
    }
    materialize();
    recalculate(1);
    return ov_left != 0;
}

void planner_set_overrides(uint8_t feed, uint8_t rapid)
{
    if (feed == feed_pct && rapid == rapid_pct)
        return;
    feed_pct = feed;
    rapid_pct = rapid;
    ov_at = tail;
    ov_left = count;
    plan_override_step();
}

/* The junction speed squared (mm/s)^2 into a new block of deltas d (mm),
 * length mm, x = its largest |d_mm| / accel and cruise speed squared cap
 * (already the lower of its own and the block before's), after the newest
 * block (prev_d, prev_mm): the acceleration along the move is mm / x, and
 * the corner's cos is -(d_prev . d) / (L_prev L); the tests below are
 * multiplied through by q = L_prev L and x (both > 0): no division but
 * for a sharp corner. (A function of its own: in plan_line its floats were
 * ~120 B of register spills.) */
static __attribute__((noinline)) float junction_sqr(const float *d, float mm, float x, float cap)
{
    float p = prev_d[0] * d[0] + prev_d[1] * d[1]; /* -cos * q */
    float q = prev_mm * mm;
    float q_lim = q * -STRAIGHT_COS;
    if (plan_lt(q_lim, p)) /* straight (plan_lt: one side not negative) */
        return cap;
    if (!plan_lt(-p, q_lim)) /* a reversal (otherwise q + p > 0) */
        return 0.0f;
    /* circle of radius r through the corner, deviating junction_deviation
     * from it: r = jd * s / (1 - s) with s = sin(t/2), v^2 = a * r, at most
     * cap. With k = a * jd and s^2 = (1 - cos t) / 2, k s^2 >= cap (1 - s^2),
     * i.e. k (1 - cos t) >= cap (1 + cos t), is enough for k s / (1 - s) >=
     * cap (s >= s^2 between 0 and 1): gentle corners (most of a curve) need
     * neither the square root nor a division. Times q x:
     * L jd (q + p) >= cap x (q - p). */
    float ljd = mm * settings.junction_deviation;
    if (!plan_lt(ljd * (q + p), cap * x * (q - p)))
        return cap;
    float sin_half = sqrtf(0.5f * (1.0f + p / q));
    float junction = ljd * sin_half / (x * (1.0f - sin_half));
    return plan_lt(cap, junction) ? cap : junction;
}

uint16_t plan_line(const float *target, float feed, uint8_t flags)
{
    int32_t cart[N_AXIS], delta[N_AXIS], motor[N_AXIS];
    if (!count)
        refresh_axis();
    for (uint8_t a = 0; a < N_AXIS; a++) {
        float t = target[a] * settings.steps_per_mm[a];
        if (!plan_lt(fabsf(t), PLAN_MAX_STEPS)) /* out of step-counter range (or NaN): refuse */
            return 0;
        cart[a] = lroundf(t);
        delta[a] = cart[a] - position[a];
    }
    plan_motor_steps(delta, motor);
    uint32_t events = 0;
    for (uint8_t a = 0; a < N_AXIS; a++) {
        uint32_t m = (uint32_t)(motor[a] < 0 ? -motor[a] : motor[a]);
        if (m > events)
            events = m;
    }
    if (events > PLAN_MAX_EVENTS) {
        /* with a margin for rounding: no piece may come out above the limit */
        uint32_t pieces = events / (PLAN_MAX_EVENTS / 10 * 9) + 1;
        return pieces < 65535u ? (uint16_t)pieces : 65535u; /* parser limits keep it far below */
    }
    if (events == 0)
        return 0;

    plan_block_t *b = &ring[head];
    b->flags = flags;
    b->line = line_number;
    for (uint8_t a = 0; a < N_AXIS; a++)
        b->steps[a] = (int16_t)motor[a];
    if (!float_same(feed, last_feed)) { /* F is modal: converted once per change */
        last_feed = feed;
        last_feed_u16 = feed < 65535.0f ? (uint16_t)(feed + 0.5f) : 65535u;
        feed_nominal = plain_nominal(feed_mm_s(last_feed_u16));
    }
    b->feed = last_feed_u16;
    /* The acceleration along the move is L / x (x: the largest |d_mm| /
     * accel), so 2 a L = 2 L^2 / x, and junction_sqr works from the deltas:
     * one division a line where there were two (1 / L and 1 / (x / L)), and
     * for a plain feed on the 328P no unit vector and no events per mm. */
    plan_motion_t m;
    float d[N_AXIS];
    float mm2 = geometry(b, &m, d);
    float x = m.inv_accel;
#if PLAN_CACHE_MOTION
    float inv_mm = motion_finish(b, &m);
#endif
    float nominal = set_nominal(b, &m, d);
    b->accel_dist2 = plan_sqr_from_float((mm2 + mm2) / x);
#if PLAN_CACHE_MOTION
    run_accel(b, &m, inv_mm);
    motion[head] = m;
#endif

    float junction = 0.0f;
    if (count) {
        float before = plan_f16_to_float((b == ring ? &ring[RING_SLOTS] : b)[-1].nominal_sqr);
        junction = junction_sqr(d, m.mm, x, plan_lt(before, nominal) ? before : nominal);
    }
    b->max_entry_sqr = plan_sqr_from_float(junction);
    b->entry_sqr = 0;

    memcpy(prev_d, d, sizeof(prev_d));
    prev_mm = m.mm;
    memcpy(position, cart, sizeof(cart));
    if (ov_left)
        ov_left++; /* the walk also caps its junction by the block before's new speed */
    uint8_t lazy = count && lazy_append(b);
    if (!lazy)
        materialize();
    head = next_index(head);
    if (count++ == 0)
        exec_exit_limit = b->accel_dist2; /* starts from rest */
    if (!lazy)
        recalculate(0);
    return 1;
}
