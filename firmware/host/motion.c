/* libmotion: the firmware's own planner, arc and segment code (src/planner.c,
 * src/arc.c, src/segment.c, src/settings.c) built for the host, driven the way
 * machine.c and the step interrupt drive them, so the server's time estimate
 * runs the same motion model as the board. Host-only glue: it never goes into
 * the AVR build.
 *
 * Calls run a program (batches of decoded lines, then its end) and return
 * when each line was acknowledged (planned) and when motion ended. Time is
 * simulated: segments run for events * (period + 1) step-timer ticks, as the
 * step interrupt runs them; lines arrive over the serial line under
 * character counting and cost the main loop `line_cpu_s` each (both host-side
 * figures, given by the caller: server/plotbridge/motion/timing.py).
 * Not reentrant: the firmware code keeps its state in globals. */
#include <math.h>
#include <string.h>
#include "arc.h"
#include "plan_split.h"
#include "planner.h"
#include "ring.h"
#include "segment.h"
#include "settings.h"

#define OP_RAPID 0
#define OP_LINE 1
#define OP_ARC_CW 2
#define OP_ARC_CCW 3
#define OP_PEN_DOWN 4
#define OP_PEN_UP 5
#define OP_DWELL 6   /* x: seconds */
#define OP_OTHER 7   /* a line that only costs its transfer and parse time */

typedef struct {
    double steps_per_mm[2], max_rate[2], accel[2];
    double junction_deviation, arc_tolerance, pen_settle_s;
    int corexy;
    int depth;          /* usable planner blocks, at most PLAN_SIZE - 1 */
    double byte_s;      /* serial seconds per byte; 0: lines are there at once */
    double line_cpu_s;  /* firmware time to parse and plan one line */
    int rx_size;        /* receive buffer the sender counts characters against */
} motion_config_t;

static motion_config_t cfg;
static double t_main;          /* when the main loop is free for the next line */
static double seg_end[SEG_SIZE]; /* when each queued segment ends */
static double exec_end;        /* when the last queued segment ends */
static double last_byte;       /* when the serial line finished the last line sent */
static float pos[N_AXIS];      /* the parser's position (gc.pos) */
static int pen_down;
static plan_block_t *ring_base; /* ring[0]: the first block after motion_configure */
/* character counting: (ack time, bytes) of lines sent, oldest first */
#define RXQ 256
static double rxq_ack[RXQ];
static int rxq_bytes[RXQ];
static int rxq_head, rxq_tail, rxq_sum;

int motion_plan_size(void) { return PLAN_SIZE - 1; }

void motion_configure(const motion_config_t *c)
{
    cfg = *c;
    if (cfg.depth < 1 || cfg.depth > PLAN_SIZE - 1)
        cfg.depth = PLAN_SIZE - 1;
    settings_defaults(&settings);
    for (int a = 0; a < N_AXIS; a++) {
        settings.steps_per_mm[a] = (float)c->steps_per_mm[a];
        settings.max_rate[a] = (float)c->max_rate[a];
        settings.accel[a] = (float)c->accel[a];
    }
    settings.junction_deviation = (float)c->junction_deviation;
    settings.arc_tolerance = (float)c->arc_tolerance;
    settings.corexy = (uint8_t)(c->corexy != 0);
    plan_reset();
    seg_reset();
    ring_base = 0;
    int32_t zero[N_AXIS] = {0};
    plan_set_position(zero);
    pos[0] = pos[1] = 0.0f;
    pen_down = 0;
    t_main = exec_end = last_byte = 0.0;
    rxq_head = rxq_tail = rxq_sum = 0;
}

/* The step interrupt's part: segments leave the ring at their end times;
 * seg_fill then refills at that moment, as the main loop would. */
static void fill_at(double now)
{
    uint8_t before = seg_head;
    seg_fill();
    for (uint8_t i = before; i != seg_head; i++) {
        const segment_t *s = &seg_ring[ring_slot(i, SEG_SIZE)];
        double start = exec_end > now ? exec_end : now; /* a starved ring restarts now */
        exec_end = start + (double)s->events * ((double)s->period + 1.0) / (double)STEP_TIMER_HZ;
        seg_end[ring_slot(i, SEG_SIZE)] = exec_end;
    }
}

/* Run segments that end by `until`, refilling as they go. */
static void run_until(double until)
{
    while (seg_head != seg_tail) {
        double end = seg_end[ring_slot(seg_tail, SEG_SIZE)];
        if (end > until)
            break;
        seg_tail++;
        fill_at(end);
    }
    fill_at(until);
}

/* Wait for one segment to end (the planner is full or motion must stop). */
static int run_one(void)
{
    if (seg_head == seg_tail) {
        fill_at(t_main);
        if (seg_head == seg_tail)
            return 0;
    }
    double end = seg_end[ring_slot(seg_tail, SEG_SIZE)];
    seg_tail++;
    if (end > t_main)
        t_main = end;
    fill_at(t_main);
    return 1;
}

static void sync_motion(void)
{
    while (plan_count() || seg_head != seg_tail)
        if (!run_one())
            break;
    if (exec_end > t_main)
        t_main = exec_end;
}

/* plan_line_split's wait: run queued blocks until the planner has room */
static uint8_t host_room(void)
{
    while (plan_count() >= (uint8_t)cfg.depth)
        run_one();
    return 1;
}

static void plan_at(const float *target, float feed, uint8_t flags)
{
    host_room();
    run_until(t_main);
    plan_line_split(target, feed, flags, host_room); /* as machine.c's line_to */
    fill_at(t_main);
}

/* The serial line under character counting: when does a line of `bytes`
 * bytes (newline included) arrive complete? */
static double arrive(int bytes)
{
    double s = last_byte;
    while (rxq_tail != rxq_head && rxq_ack[rxq_tail % RXQ] <= s) {
        rxq_sum -= rxq_bytes[rxq_tail % RXQ];
        rxq_tail++;
    }
    while (rxq_tail != rxq_head && (rxq_sum + bytes > cfg.rx_size || rxq_head - rxq_tail >= RXQ)) {
        if (rxq_ack[rxq_tail % RXQ] > s)
            s = rxq_ack[rxq_tail % RXQ];
        rxq_sum -= rxq_bytes[rxq_tail % RXQ];
        rxq_tail++;
    }
    last_byte = s + bytes * cfg.byte_s;
    return last_byte;
}

static void acked(int bytes)
{
    rxq_ack[rxq_head % RXQ] = t_main;
    rxq_bytes[rxq_head % RXQ] = bytes;
    rxq_head++;
    rxq_sum += bytes;
}

/* Runs n lines: kind[k] (OP_*), end point x, y (arcs: centre offsets i, j),
 * feed (mm/min), bytes (line length with its newline). ack[k]: seconds when
 * line k was acknowledged. The program goes on in the next call (the server
 * feeds a long one in batches while it writes the rest); motion_end ends it. */
void motion_feed(int n, const uint8_t *kind, const float *x, const float *y, const float *i,
                 const float *j, const float *feed, const uint16_t *bytes, double *ack)
{
    for (int k = 0; k < n; k++) {
        double at = arrive(bytes[k]);
        if (at > t_main) {
            run_until(at);
            t_main = at;
        }
        t_main += cfg.line_cpu_s;
        float target[N_AXIS] = {x[k], y[k]};
        switch (kind[k]) {
        case OP_RAPID:
        case OP_LINE:
            plan_at(target, feed[k], kind[k] == OP_RAPID ? PB_RAPID : 0);
            pos[0] = target[0];
            pos[1] = target[1];
            break;
        case OP_ARC_CW:
        case OP_ARC_CCW: {
            arc_t arc;
            float center[N_AXIS] = {pos[0] + i[k], pos[1] + j[k]};
            if (!arc_init(&arc, pos, target, center, kind[k] == OP_ARC_CW, settings.arc_tolerance)) {
                for (uint16_t s = 1; s <= arc.segments; s++) {
                    float p[N_AXIS];
                    arc_point(&arc, s, p);
                    plan_at(p, feed[k], 0);
                }
            }
            pos[0] = target[0];
            pos[1] = target[1];
            break;
        }
        case OP_PEN_DOWN:
        case OP_PEN_UP:
            sync_motion();
            if (pen_down != (kind[k] == OP_PEN_DOWN)) {
                pen_down = kind[k] == OP_PEN_DOWN;
                t_main += cfg.pen_settle_s;
            }
            break;
        case OP_DWELL:
            sync_motion();
            t_main += x[k];
            break;
        default:
            run_until(t_main);
            break;
        }
        ack[k] = t_main;
        acked(bytes[k]);
    }
}

/* The end of the program fed: returns the time when motion (and a final pen
 * settle) ended. */
double motion_end(void)
{
    sync_motion();
    return t_main;
}

/* For the differential test: plan lines with nothing executing (no timing),
 * then read the queued blocks. The library is built with packed structs, so a
 * block's bytes are laid out as avr-gcc lays them out in the firmware's RAM. */

void motion_plan(int n, const uint8_t *kind, const float *x, const float *y, const float *i,
                 const float *j, const float *feed)
{
    for (int k = 0; k < n; k++) {
        float target[N_AXIS] = {x[k], y[k]};
        if (kind[k] == OP_ARC_CW || kind[k] == OP_ARC_CCW) {
            arc_t arc;
            float center[N_AXIS] = {pos[0] + i[k], pos[1] + j[k]};
            if (!arc_init(&arc, pos, target, center, kind[k] == OP_ARC_CW, settings.arc_tolerance))
                for (uint16_t s = 1; s <= arc.segments && plan_free(); s++) {
                    float p[N_AXIS];
                    arc_point(&arc, s, p);
                    plan_line(p, feed[k], 0);
                }
        } else if (plan_free()) {
            uint8_t was_empty = !plan_count();
            plan_line(target, feed[k], kind[k] == OP_RAPID ? PB_RAPID : 0);
            if (was_empty && plan_count() && !ring_base)
                ring_base = plan_current(); /* after plan_reset the first block is ring[0] */
        }
        pos[0] = target[0];
        pos[1] = target[1];
    }
}

/* Copies the queued blocks, oldest first, into out (room for max), with
 * their planned entries written out (the lazy backward pass keeps some
 * relative); returns how many. */
int motion_blocks(plan_block_t *out, int max)
{
    plan_block_t *b = plan_current();
    int n = 0;
    for (; b && ring_base && n < plan_count() && n < max; n++) {
        out[n] = *b;
        out[n].entry_sqr = plan_entry_sqr(b);
        b = b + 1 == ring_base + (PLAN_SIZE - 1) ? ring_base : b + 1;
    }
    return n;
}

int motion_block_size(void) { return (int)sizeof(plan_block_t); }
