/* Arc chords, planner junctions and exact steps, segment profiles. */
#include <math.h>
#include <string.h>
#include "arc.h"
#include "check.h"
#include "planner.h"
#include "segment.h"
#include "settings.h"
#include "status.h"
#include "tests.h"

void test_arc_segments(void)
{
    arc_t arc;
    float s[2] = {10, 0}, t[2] = {0, 10}, c[2] = {0, 0};
    CHECK(arc_init(&arc, s, t, c, 0, 0.002f) == STATUS_OK);
    CHECK_NEAR(arc.sweep, M_PI / 2, 1e-5);
    /* every chord's sagitta within the tolerance, every vertex on the circle */
    float prev[2] = {10, 0};
    double worst = 0;
    for (uint16_t k = 1; k <= arc.segments; k++) {
        float p[2];
        arc_point(&arc, k, p);
        CHECK_NEAR(hypot(p[0], p[1]), 10, 1e-4);
        double mx = (prev[0] + p[0]) / 2.0, my = (prev[1] + p[1]) / 2.0;
        double sag = 10.0 - hypot(mx, my);
        if (sag > worst)
            worst = sag;
        memcpy(prev, p, sizeof(p));
    }
    CHECK(worst <= 0.002 + 1e-5);
    CHECK(worst > 0.0005); /* and not absurdly many chords */
    CHECK(prev[0] == 0.0f && prev[1] == 10.0f); /* the last point is the exact target */
    /* clockwise the long way round */
    CHECK(arc_init(&arc, s, t, c, 1, 0.002f) == STATUS_OK);
    CHECK_NEAR(arc.sweep, -1.5 * M_PI, 1e-5);
    /* degenerate */
    CHECK(arc_init(&arc, c, t, c, 0, 0.002f) == ERR_INVALID_TARGET);
    /* huge radius: bounded count, no infinite loop */
    float big_s[2] = {0, 0}, big_t[2] = {1, 0}, big_c[2] = {0.5f, -90000};
    CHECK(arc_init(&arc, big_s, big_t, big_c, 1, 0.002f) == STATUS_OK);
    CHECK(arc.segments >= 1 && arc.segments <= ARC_MAX_SEGMENTS);
}

void test_arc_full_circle(void)
{
    arc_t arc;
    float s[2] = {20, 10}, c[2] = {10, 10};
    CHECK(arc_init(&arc, s, s, c, 1, 0.01f) == STATUS_OK);
    CHECK_NEAR(arc.sweep, -2 * M_PI, 1e-5);
    for (uint16_t k = 1; k < arc.segments; k += 7) {
        float p[2];
        double ang = -2 * M_PI * k / arc.segments;
        arc_point(&arc, k, p);
        CHECK_NEAR(p[0], 10 + 10 * cos(ang), 1e-3);
        CHECK_NEAR(p[1], 10 + 10 * sin(ang), 1e-3);
    }
}

static plan_motion_t block_motion(const plan_block_t *b)
{
    plan_motion_t m;
    plan_block_motion(b, &m);
    return m;
}

static double nominal_sqr(const plan_block_t *b) { return plan_f16_to_float(b->nominal_sqr); }

/* the stored cruise speed: never above v, and within the 16-bit format's 2^-8 */
#define CHECK_SPEED(b, v) \
    CHECK(sqrt(nominal_sqr(b)) <= (v) * (1 + 1e-6) && sqrt(nominal_sqr(b)) >= (v) * (1 - 1.0 / 256))

static void fresh_planner(void)
{
    settings_defaults(&settings);
    plan_reset();
    seg_reset();
    int32_t zero[2] = {0, 0};
    plan_set_position(zero);
}

void test_planner_junctions(void)
{
    fresh_planner();
    float a[2] = {10, 0}, b[2] = {20, 0}, c[2] = {20, 10}, d[2] = {10, 10};
    CHECK(plan_line(a, 3000, 0));
    CHECK(plan_line(b, 3000, 0));
    CHECK(plan_line(c, 3000, 0));
    CHECK(plan_line(d, 3000, 0));
    plan_block_t *first = plan_current();
    CHECK(first && plan_count() == 4);
    /* straight continuation: junction limited only by the nominal speed */
    CHECK_NEAR(plan_sqr_to_float(first[1].max_entry_sqr), 50.0 * 50.0, 2500.0 / 128); /* 16-bit cap */
    /* a 90 degree corner: v^2 = a * jd * sin(t/2) / (1 - sin(t/2)) */
    double sh = sqrt(0.5);
    CHECK_NEAR(plan_sqr_to_float(first[2].max_entry_sqr), 1000.0 * 0.02 * sh / (1 - sh),
               1.0 / PLAN_SQR_SCALE);
    /* a full reversal stops */
    fresh_planner();
    CHECK(plan_line(a, 3000, 0));
    float back[2] = {0, 0};
    CHECK(plan_line(back, 3000, 0));
    CHECK(plan_current()[1].max_entry_sqr == 0);
    /* the last block can always stop: backward pass bound */
    fresh_planner();
    float tiny1[2] = {0.5f, 0}, tiny2[2] = {1.0f, 0};
    plan_line(tiny1, 6000, 0);
    plan_line(tiny2, 6000, 0);
    plan_block_t *t = plan_current();
    CHECK(plan_sqr_to_float(plan_entry_sqr(&t[1])) <= 2 * 1000 * 0.5);
    /* zero-length moves queue nothing */
    CHECK(plan_line(tiny2, 6000, 0) == 0);
    /* moves beyond the 16-bit step counters are refused, with the pieces to cut them into */
    fresh_planner();
    float far[2] = {300, 220};
    settings.steps_per_mm[0] = 400;
    CHECK(plan_line(far, 3000, 0) == 5 && plan_count() == 0); /* 120,000 events, at most 27,000 a piece */
    settings.corexy = 1;       /* motor A: 120,000 + 17,600 */
    CHECK(plan_line(far, 3000, 0) == 6);
    settings.corexy = 0;
    settings.steps_per_mm[0] = 80;
    CHECK(plan_line(far, 3000, 0) == 1); /* 24,000: fits */
    fresh_planner();
    settings.steps_per_mm[0] = 400;
    float fifth[2] = {60, 44};
    CHECK(plan_line(fifth, 3000, 0) == 1);
    settings_defaults(&settings);
    /* rapid uses the axis maximum */
    fresh_planner();
    plan_line(a, 0, PB_RAPID);
    CHECK_SPEED(plan_current(), 100);
    /* diagonal: acceleration and speed limited per axis */
    fresh_planner();
    settings.max_rate[1] = 600;
    float diag[2] = {10, 10};
    plan_line(diag, 100000, 0);
    CHECK_SPEED(plan_current(), 10 * sqrt(2));
    settings_defaults(&settings);
    /* the junction rule across all corner angles, on both sides of the
     * nominal cap (gentle corners take a shortcut to the cap) */
    for (int deg = 1; deg < 180; deg++) {
        fresh_planner();
        double t = deg * M_PI / 180.0;
        float p1[2] = {20, 20}, p2[2] = {20 + 20 * (float)cos(t), 20 + 20 * (float)sin(t)};
        CHECK(plan_line(p1, 6000, 0) && plan_line(p2, 6000, 0));
        plan_block_t *q = plan_current();
        /* the planner sees the move between whole steps */
        double dx = round(p2[0] * 80.0) / 80.0 - 20, dy = round(p2[1] * 80.0) / 80.0 - 20;
        double ux = dx / hypot(dx, dy), uy = dy / hypot(dx, dy);
        double u0 = sqrt(0.5);
        double c = -(u0 * ux + u0 * uy);
        double sh = sqrt(0.5 * (1 - c));
        double accel = block_motion(&q[1]).accel;
        double expect = accel * 0.02 * sh / (1 - sh);
        if (expect > nominal_sqr(&q[1])) /* capped by the cruise speeds (as stored) */
            expect = nominal_sqr(&q[1]);
        CHECK_NEAR(plan_sqr_to_float(q[1].max_entry_sqr), expect, expect * 1e-4 + 2.0 / PLAN_SQR_SCALE);
    }
}

/* Run the segment preparer to the end, as the step interrupt would consume it. */
typedef struct {
    uint32_t events, segments;
    double time, max_speed, max_accel, last_speed, last_dt;
    int64_t steps[2];
} run_t;

static void drain(run_t *r, double mm_per_event)
{
    while (seg_tail != seg_head) {
        segment_t *s = &seg_ring[seg_tail & (SEG_SIZE - 1)];
        const step_block_t *b = s->block;
        if (s->flags & SEG_FIRST) {
            for (int a = 0; a < 2; a++)
                r->steps[a] += (b->dir_negative & (1 << a)) ? -(int64_t)b->steps[a] : (int64_t)b->steps[a];
        }
        double dt = (double)s->events * (s->period + 1) / STEP_TIMER_HZ;
        double v = s->events * mm_per_event / dt;
        /* each segment's rate is its average: compare midpoints */
        double gap = 0.5 * (dt + r->last_dt);
        if (r->segments && fabs(v - r->last_speed) / gap > r->max_accel)
            r->max_accel = fabs(v - r->last_speed) / gap;
        r->last_dt = dt;
        if (v > r->max_speed)
            r->max_speed = v;
        r->last_speed = v;
        r->time += dt;
        r->events += s->events;
        r->segments++;
        seg_tail++;
    }
}

void test_planner_block_math(void)
{
    /* 16-bit speeds: never above the value, within 2^-7 below, exact where the
     * float has no more bits, monotonic, and 0 for what is not positive */
    plan_f16_t prev = 0;
    for (double v = 1e-4; v < 1e8; v *= 1.0137) {
        float f = (float)v;
        plan_f16_t h = plan_f16_from_float(f);
        float back = plan_f16_to_float(h);
        CHECK(back <= f && back >= f * (1 - 1.0 / 128));
        CHECK(h >= prev);
        prev = h;
    }
    CHECK(plan_f16_to_float(plan_f16_from_float(2500.0f)) == 2496.0f);
    CHECK(plan_f16_to_float(plan_f16_from_float(1024.0f)) == 1024.0f);
    CHECK(plan_f16_from_float(0.0f) == 0 && plan_f16_from_float(-3.0f) == 0 &&
          plan_f16_from_float(NAN) == 0);
    /* squared speeds in 1/64 (mm/s)^2: rounded down, saturated, stops for junk */
    for (double v = 0.01; v < 5e6; v *= 1.37) {
        float back = plan_sqr_to_float(plan_sqr_from_float((float)v));
        CHECK(back <= (float)v && back > (float)v - 1.0f / PLAN_SQR_SCALE - (float)v * 1e-6f);
    }
    CHECK(plan_sqr_from_float(1e12f) == PLAN_SQR_MAX && plan_sqr_from_float(-1.0f) == 0 &&
          plan_sqr_from_float(NAN) == 0);

    /* the planned entry speeds of a queue of short blocks round a curve with
     * a corner against the same passes in double precision from the float
     * geometry (the whole-step targets): within the fixed-point roundings */
    fresh_planner();
    enum { N = 30 };
    double px[N + 1], py[N + 1];
    px[0] = py[0] = 0;
    for (int k = 1; k <= N; k++) {
        double t = k < 20 ? k * 0.08 : 1.6 - (k - 19) * 0.3; /* gentle curve, then sharp turns */
        float p[2] = {(float)(px[k - 1] + 0.6 * cos(t)), (float)(py[k - 1] + 0.6 * sin(t))};
        CHECK(plan_line(p, 4000, 0) == 1);
        px[k] = round(p[0] * 80.0) / 80.0;
        py[k] = round(p[1] * 80.0) / 80.0;
    }
    CHECK(plan_count() == N);
    double limit[N], gain[N], entry[N];
    double v_max = 4000.0 / 60.0, ux0 = 0, uy0 = 0;
    for (int k = 0; k < N; k++) {
        double dx = px[k + 1] - px[k], dy = py[k + 1] - py[k], len = hypot(dx, dy);
        double ux = dx / len, uy = dy / len;
        double accel = 1000.0 / fmax(fabs(ux), fabs(uy));
        gain[k] = 2 * accel * len;
        limit[k] = 0;
        if (k) {
            double c = -(ux0 * ux + uy0 * uy), sh = sqrt(0.5 * (1 - c));
            limit[k] = fmin(v_max * v_max, accel * 0.02 * sh / (1 - sh));
        }
        ux0 = ux;
        uy0 = uy;
    }
    double next = 0; /* backward: stop at the end of the queue */
    for (int k = N - 1; k >= 0; k--)
        next = entry[k] = fmin(limit[k], next + gain[k]);
    entry[0] = 0; /* forward: the first block starts from rest */
    for (int k = 1; k < N; k++)
        entry[k] = fmin(entry[k], entry[k - 1] + gain[k - 1]);
    const plan_block_t *q = plan_current();
    for (int k = 1; k < N; k++) {
        double got = plan_sqr_to_float(plan_entry_sqr(&q[k]));
        CHECK(got <= entry[k] * (1 + 1e-4) + 1e-3);
        CHECK(got >= entry[k] * (1 - 1.0 / 64) - 0.1); /* the 16-bit cruise cap, the 1/64 floors */
    }
}

/* The cruise speed of every block is min(F, each moving axis's max rate /
 * |u_axis|), raised to the slowest step rate, whatever the feed's history:
 * a feed no limit can bind is converted once per F change and reused in
 * every direction (plain_nominal), so the feeds here sit on both sides of
 * each limit and each one runs in many directions, unequal axes included. */
void test_planner_cruise_limits(void)
{
    static const float feeds[] = {100, 300, 383, 384, 385, 600, 2990, 2996, 2997, 2998,
                                  3000, 3003, 5990, 6000, 6010, 9000};
    for (uint8_t pass = 0; pass < 2; pass++) {
        fresh_planner();
        settings.max_rate[0] = 3000;
        settings.max_rate[1] = 6000;
        if (pass) {
            settings.steps_per_mm[1] = 5; /* 32 steps/s is 6.4 mm/s along Y */
            settings.max_rate[1] = 600;
        }
        for (uint8_t f = 0; f < sizeof(feeds) / sizeof(feeds[0]); f++) {
            plan_reset();
            int32_t zero[2] = {0, 0};
            plan_set_position(zero);
            float at[2] = {0, 0};
            for (uint8_t k = 0; k < 24; k++) {
                double ang = k * (2 * M_PI / 24) + 0.01;
                float to[2] = {at[0] + (float)(7 * cos(ang)), at[1] + (float)(7 * sin(ang))};
                CHECK(plan_line(to, feeds[f], 0) == 1);
                memcpy(at, to, sizeof(at));
                const plan_block_t *b = &plan_current()[k];
                double d[2], mm = 0, events = 0;
                for (uint8_t a = 0; a < 2; a++) {
                    d[a] = b->steps[a] / (double)settings.steps_per_mm[a];
                    mm += d[a] * d[a];
                    if (fabs((double)b->steps[a]) > events)
                        events = fabs((double)b->steps[a]);
                }
                mm = sqrt(mm);
                double v = feeds[f] / 60.0;
                for (uint8_t a = 0; a < 2; a++)
                    if (b->steps[a] && settings.max_rate[a] / 60.0 * mm / fabs(d[a]) < v)
                        v = settings.max_rate[a] / 60.0 * mm / fabs(d[a]);
                if (v * events / mm < 32)
                    v = 32 / (events / mm);
                CHECK_SPEED(b, v);
            }
        }
    }
    settings_defaults(&settings);
}

void test_planner_exact_steps(void)
{
    /* thousands of short segments along a spiral: the prepared steps add up
     * exactly to the rounded target, with no drift */
    fresh_planner();
    run_t r;
    memset(&r, 0, sizeof(r));
    float p[2] = {0, 0};
    for (int i = 1; i <= 3000; i++) {
        float ang = i * 0.01f;
        p[0] = 150 + (10 + i * 0.01f) * cosf(ang);
        p[1] = 110 + (10 + i * 0.01f) * sinf(ang);
        while (!plan_free()) {
            seg_fill();
            drain(&r, 1.0 / 80.0);
        }
        plan_line(p, 3000, 0);
    }
    for (int guard = 0; guard < 100000 && (plan_count() || seg_head != seg_tail); guard++) {
        seg_fill();
        drain(&r, 1.0 / 80.0);
    }
    CHECK(plan_count() == 0);
    CHECK(r.steps[0] == lroundf(p[0] * 80));
    CHECK(r.steps[1] == lroundf(p[1] * 80));
    /* and the planner's own position agrees */
    int32_t pos[2];
    plan_get_position(pos);
    CHECK(pos[0] == r.steps[0] && pos[1] == r.steps[1]);
}

void test_segments_profile(void)
{
    /* one 100 mm move at 3000 mm/min, a = 1000: trapezoid time is
     * L / v + v / a = 2 + 0.05 s */
    fresh_planner();
    float t[2] = {100, 0};
    plan_line(t, 3000, 0);
    run_t r;
    memset(&r, 0, sizeof(r));
    for (int guard = 0; guard < 10000 && (plan_count() || seg_head != seg_tail); guard++) {
        seg_fill();
        drain(&r, 1.0 / 80.0);
    }
    CHECK(r.events == 8000);
    CHECK(r.steps[0] == 8000 && r.steps[1] == 0);
    CHECK_NEAR(r.time, 2.05, 2.05 * 0.02);
    CHECK(r.max_speed <= 50 * 1.02);
    /* segment to segment speed changes stay near the configured acceleration
     * (each segment's rate is its average, so allow for the quantization) */
    CHECK(r.max_accel <= 1000 * 1.6);
    /* a triangle: too short to reach the cruise speed: t = 2 sqrt(L / a) */
    fresh_planner();
    float s[2] = {1, 0};
    plan_line(s, 6000, 0);
    memset(&r, 0, sizeof(r));
    for (int guard = 0; guard < 10000 && (plan_count() || seg_head != seg_tail); guard++) {
        seg_fill();
        drain(&r, 1.0 / 80.0);
    }
    CHECK(r.events == 80);
    CHECK_NEAR(r.time, 2 * sqrt(1.0 / 1000), 0.003);
}

void test_segments_hold(void)
{
    fresh_planner();
    float t[2] = {100, 0};
    plan_line(t, 3000, 0);
    run_t r;
    memset(&r, 0, sizeof(r));
    for (int i = 0; i < 10; i++) { /* get up to speed: 10 x 7 segments of 8 ms */
        seg_fill();
        drain(&r, 1.0 / 80.0);
    }
    uint32_t at_hold = r.events;
    seg_hold(1);
    for (int guard = 0; guard < 1000 && !seg_hold_reached(); guard++) {
        seg_fill();
        drain(&r, 1.0 / 80.0);
    }
    CHECK(seg_hold_reached());
    /* stopping from 50 mm/s at 1000 mm/s^2 takes 1.25 mm (100 steps) */
    CHECK(r.events - at_hold >= 90 && r.events - at_hold <= 115);
    CHECK(r.events < 8000);
    seg_fill();
    CHECK(seg_head == seg_tail); /* nothing more while held */
    seg_hold(0);
    for (int guard = 0; guard < 10000 && (plan_count() || seg_head != seg_tail); guard++) {
        seg_fill();
        drain(&r, 1.0 / 80.0);
    }
    CHECK(r.events == 8000);
}

void test_planner_overrides(void)
{
    /* three straight 10 mm moves at F3000 (50 mm/s), a rapid and a jog */
    fresh_planner();
    float p1[2] = {10, 0}, p2[2] = {20, 0}, p3[2] = {30, 0}, p4[2] = {40, 0}, p5[2] = {50, 0};
    CHECK(plan_line(p1, 3000, 0) && plan_line(p2, 3000, 0) && plan_line(p3, 3000, 0));
    CHECK(plan_line(p4, 0, PB_RAPID) && plan_line(p5, 1200, PB_JOG));
    plan_block_t *q = plan_current();
    CHECK_SPEED(&q[1], 50);
    CHECK_NEAR(plan_sqr_to_float(q[1].max_entry_sqr), 2500, 2500.0 / 128); /* the 16-bit cruise cap */
    /* feed 50 %, rapids 25 %: every queued block, the oldest too */
    planner_set_overrides(50, 25);
    while (plan_override_step())
        ;
    for (int i = 0; i < 3; i++)
        CHECK_SPEED(&q[i], 25);
    CHECK_SPEED(&q[3], 100 * 0.25); /* $110 6000 mm/min */
    CHECK_SPEED(&q[4], 20);         /* the jog keeps F1200 */
    /* junctions capped by the new speeds, and the queue replanned */
    CHECK(plan_sqr_to_float(q[1].max_entry_sqr) <= 625 + 1e-3);
    CHECK(plan_sqr_to_float(q[4].max_entry_sqr) <= 400 + 1e-3);
    for (int i = 1; i < 5; i++)
        CHECK(plan_entry_sqr(&q[i]) <= q[i].max_entry_sqr);
    /* later blocks are planned with the overrides too */
    float p6[2] = {60, 0};
    CHECK(plan_line(p6, 3000, 0));
    CHECK_SPEED(&q[5], 25);
    /* back to 100 %: programmed speeds again */
    planner_set_overrides(100, 100);
    while (plan_override_step())
        ;
    CHECK_SPEED(&q[0], 50);
    CHECK_SPEED(&q[3], 100);
    /* the segment preparer follows a lowered speed inside the executing block */
    fresh_planner();
    float far[2] = {100, 0};
    plan_line(far, 3000, 0);
    run_t r;
    memset(&r, 0, sizeof(r));
    for (int i = 0; i < 20; i++) { /* up to 50 mm/s */
        seg_fill();
        drain(&r, 1.0 / 80.0);
    }
    CHECK(r.last_speed > 45);
    planner_set_overrides(20, 100);
    for (int i = 0; i < 20; i++) {
        seg_fill();
        drain(&r, 1.0 / 80.0);
    }
    CHECK(r.last_speed < 10 * 1.05 && r.last_speed > 10 * 0.95);
    planner_set_overrides(100, 100);
    for (int guard = 0; guard < 100000 && (plan_count() || seg_head != seg_tail); guard++) {
        seg_fill();
        drain(&r, 1.0 / 80.0);
    }
    CHECK(r.events == 8000);
}

/* An override change recomputes the queue a slice at a time, oldest first;
 * blocks executed before the walk gets to them are skipped, and the end
 * result is the queue planned with the override from the start. */
void test_planner_override_slices(void)
{
    enum { N = 30, DONE = 6 };
    float p[N][2];
    for (int i = 0; i < N; i++) { /* 2 mm chords of a gentle curve: real junctions */
        double a = i * 0.05;
        p[i][0] = (float)(20 + 40 * sin(a));
        p[i][1] = (float)(60 - 40 * cos(a));
    }
    fresh_planner();
    for (int i = 0; i < N; i++)
        CHECK(plan_line(p[i], 3000, 0) == 1);
    plan_block_t *q = plan_current();
    plan_f16_t before = q[10].nominal_sqr;
    planner_set_overrides(50, 100);
    CHECK_SPEED(&q[0], 25);
    CHECK_SPEED(&q[3], 25);
    CHECK(q[4].nominal_sqr == before && q[10].nominal_sqr == before); /* not yet */
    for (int i = 0; i < DONE; i++) /* the steppers overtake the walk */
        plan_discard_current();
    int slices = 0;
    while (plan_override_step())
        slices++;
    CHECK(slices == (N - DONE) / 4 - 1);
    for (int i = 1; i < N - DONE; i++)
        CHECK(plan_entry_sqr(&plan_current()[i]) <= plan_current()[i].max_entry_sqr);
    /* the same lines planned with the override already set */
    plan_block_t walked[N];
    memcpy(walked, plan_current(), sizeof(plan_block_t) * (N - DONE));
    fresh_planner();
    int32_t from[2] = {lroundf(p[DONE - 1][0] * 80), lroundf(p[DONE - 1][1] * 80)};
    plan_set_position(from);
    for (int i = DONE; i < N; i++)
        CHECK(plan_line(p[i], 3000, 0) == 1);
    q = plan_current();
    for (int i = 1; i < N - DONE; i++) {
        CHECK(walked[i].nominal_sqr == q[i].nominal_sqr);
        CHECK(walked[i].max_entry_sqr == q[i].max_entry_sqr);
    }
    plan_reset();
    planner_set_overrides(100, 100);
}

void test_settings(void)
{
    settings_t s;
    settings_defaults(&s);
    float v;
    CHECK(settings_get(&s, 100, &v) && v == 80.0f);
    CHECK(settings_get(&s, 131, &v) && v == 220.0f);
    CHECK(settings_get(&s, 62, &v) && v == 150.0f);
    CHECK(settings_get(&s, 11, &v) && fabsf(v - 0.02f) < 1e-7f);
    CHECK(!settings_get(&s, 7, &v));
    CHECK(settings_set(&s, 110, 5000) == STATUS_OK && s.max_rate[0] == 5000.0f);
    CHECK(settings_set(&s, 110, -1) == ERR_NEGATIVE);
    CHECK(settings_set(&s, 100, 0) == ERR_INVALID_DOLLAR);
    CHECK(settings_set(&s, 0, 2) == ERR_STEP_PULSE);
    CHECK(settings_set(&s, 20, 0.5f) == STATUS_OK && s.soft_limits == 0); /* truncated, as GRBL */
    CHECK(settings_set(&s, 1, 1.5f) == STATUS_OK && s.idle_delay_ms == 1);
    CHECK(settings_set(&s, 20, 2) == ERR_INVALID_DOLLAR);
    CHECK(settings_set(&s, 60, 3000) == ERR_INVALID_DOLLAR);
    CHECK(settings_set(&s, 61, 2100) == STATUS_OK && s.pen_down_us == 2100);
    CHECK(settings_set(&s, 99, 1) == ERR_INVALID_DOLLAR);
    CHECK(settings_set(&s, 63, 1) == STATUS_OK && s.corexy == 1);
    CHECK(!settings_is_integer(100) && !settings_is_integer(11) && settings_is_integer(22) && settings_is_integer(62));
    /* every listed id reads back */
    for (uint8_t i = 0; i < settings_count; i++)
        CHECK(settings_get(&s, settings_id(i), &v));
    /* the checksum sees a changed byte and swapped bytes */
    uint8_t data[4] = {1, 2, 3, 4}, swapped[4] = {2, 1, 3, 4}, changed[4] = {1, 2, 3, 5};
    CHECK(settings_checksum(data, 4) != settings_checksum(swapped, 4));
    CHECK(settings_checksum(data, 4) != settings_checksum(changed, 4));
}

/* The planned entries of every queued block against the two passes run in
 * full over the queue (integers, the same fixed point): equal, whatever the
 * lazy backward pass kept relative, after every block queued, executed or
 * replanned by an override. The exit limit of the executing block is the
 * planner's own (from rest, then its planned entry plus its gain). */
static void check_full_passes(plan_sqr_t exec_limit)
{
    const plan_block_t *q = plan_current();
    uint8_t n = plan_count();
    plan_sqr_t e[64], next = 0;
    for (int k = n - 1; k >= 1; k--) {
        const plan_block_t *b = &q[k];
        e[k] = next + b->accel_dist2 < b->max_entry_sqr ? next + b->accel_dist2 : b->max_entry_sqr;
        next = e[k];
    }
    plan_sqr_t reach = exec_limit;
    for (int k = 1; k < n; k++) {
        if (e[k] > reach)
            e[k] = reach;
        reach = e[k] + q[k].accel_dist2;
        CHECK(plan_entry_sqr(&q[k]) == e[k]);
    }
}

void test_planner_lazy_passes(void)
{
    fresh_planner();
    settings.accel[0] = settings.accel[1] = 3000;
    settings.max_rate[0] = settings.max_rate[1] = 30000;
    uint32_t seed = 12345;
    float x = 0, y = 0, heading = 0;
    plan_sqr_t exec_limit = 0;
    /* the host ring is not rotated between checks: q[k] below walks it from
     * its first slot, so the queue is drained whole before it wraps */
    static const float lengths[8] = {0.3f, 0.5f, 0.5f, 0.5f, 0.5f, 1.0f, 4.0f, 12.0f};
    for (int round = 0; round < 40; round++) {
        int blocks = 3 + round * 7 % (PLAN_SIZE - 4);
        for (int k = 0; k < blocks; k++) {
            seed = seed * 1103515245u + 12345u;
            uint32_t r = seed >> 8;
            /* corners of every sharpness now and then: junction limits vary */
            heading += (r & 3) == 0 ? (float)(r % 97) * ((r & 12) ? 0.002f : 0.016f)
                                    : (float)((int)(r % 21) - 10) * 0.004f;
            float len = k == 0 && round % 4 ? 80.0f : lengths[(r >> 5) & 7]; /* a long lead: no cap */
            x += len * cosf(heading);
            y += len * sinf(heading);
            if (x < 5 || x > 290 || y < 5 || y > 200) {
                x -= len * cosf(heading);
                y -= len * sinf(heading);
                heading += 3.0f;
                x += len * cosf(heading);
                y += len * sinf(heading);
            }
            float p[2] = {x, y};
            uint8_t was = plan_count();
            CHECK(plan_line(p, (float)(3000 + (r >> 12) % 4 * 5000), 0) == 1);
            if (!was)
                exec_limit = plan_current()->accel_dist2;
            check_full_passes(exec_limit);
            if (k == blocks / 2 && round % 3 == 1) { /* an override mid-queue */
                planner_set_overrides(round % 2 ? 60 : 100, 100);
                while (plan_override_step())
                    ;
                check_full_passes(exec_limit);
            }
        }
        /* executed, oldest first: the next block's planned entry becomes fixed */
        while (plan_count() > 1) {
            plan_discard_current();
            exec_limit = plan_entry_sqr(plan_current()) + plan_current()->accel_dist2;
            check_full_passes(exec_limit);
        }
        plan_discard_current();
        plan_reset();
    }
    /* a corner among lazy blocks with less room to its limit than the older
     * ones have: it reaches its limit first */
    fresh_planner();
    settings.accel[0] = settings.accel[1] = 3000;
    settings.max_rate[0] = settings.max_rate[1] = 30000;
    float lead[2] = {80, 10};
    CHECK(plan_line(lead, 18000, 0) == 1);
    exec_limit = plan_current()->accel_dist2;
    for (int k = 1; k <= 24; k++) {
        float h = k <= 10 ? 0.0f : 0.12f, p[2] = {80 + (k <= 10 ? k * 0.5f : 5 + (k - 10) * 0.5f * cosf(h)),
                                                   10 + (k <= 10 ? 0 : (k - 10) * 0.5f * sinf(h))};
        CHECK(plan_line(p, 18000, 0) == 1);
        check_full_passes(exec_limit);
    }
    planner_set_overrides(100, 100);
    fresh_planner();
}

