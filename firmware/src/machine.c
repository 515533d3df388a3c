#include <avr/interrupt.h>
#include <avr/sleep.h>
#include <avr/wdt.h>
#include <math.h>
#include <stddef.h>
#include <string.h>
#include "arc.h"
#include "float_bits.h"
#include "inputs.h"
#include "machine.h"
#include "plan_split.h"
#include "planner.h"
#include "realtime.h"
#include "report.h"
#include "ring.h"
#include "segment.h"
#include "serial.h"
#include "servo.h"
#include "settings.h"
#include "status.h"
#include "stepper.h"

#define SOFT_LIMIT_EPS 0.0005f

machine_t mach;
gc_state_t gc;
static uint32_t idle_since;

uint32_t machine_ms(void) { return timebase_ms(); }

void machine_init(void)
{
    plan_reset();
    seg_reset();
    gc_init(&gc);
    machine_resync();
}

void machine_resync(void)
{
    int32_t motor[N_AXIS], cart[N_AXIS];
    stepper_get_position(motor);
    plan_cart_from_motor(motor, cart);
    plan_set_position(cart);
    for (uint8_t a = 0; a < N_AXIS; a++)
        gc.pos[a] = (float)cart[a] / settings.steps_per_mm[a];
}

uint8_t machine_moving(void)
{
    return stepper_busy() || plan_count() || seg_head != seg_tail || mach.dwelling;
}

void machine_alarm(uint8_t code)
{
    stepper_halt();
    plan_reset();
    seg_reset();
    machine_resync();
    machine_pen_up_now();
    mach.alarm = code;
    mach.hold = mach.jog = mach.jog_cancel = 0;
    seg_hold(0);
    mach.abort = 1;
    if (code != ALARM_LOCKED)
        report_alarm(code);
}

/* a hold (or M0) has brought everything to a stop */
static uint8_t hold_stopped(void)
{
    return (seg_hold_reached() || !machine_moving()) && !stepper_busy();
}

/* WCO and Ov as GRBL refreshes them: in the report after a change (the
 * countdown set to 0), then every `every`+1-th one */
static uint8_t due(uint8_t *countdown, uint8_t every)
{
    if (*countdown) {
        (*countdown)--;
        return 0;
    }
    *countdown = every;
    return 1;
}

void machine_report_status(void)
{
    uint8_t in = inputs_read();
    uint8_t busy = machine_moving();
    PGM_P state = PSTR("Idle");
    if (mach.sleep)
        state = PSTR("Sleep");
    else if (mach.alarm)
        state = PSTR("Alarm");
    else if (mach.homing)
        state = PSTR("Home");
    else if (mach.check)
        state = PSTR("Check");
    else if (mach.hold && mach.jog)
        state = PSTR("Jog"); /* a jog being cancelled, as GRBL reports it */
    else if (mach.hold)
        state = hold_stopped() ? PSTR("Hold:0") : PSTR("Hold:1");
    else if (busy)
        state = mach.jog ? PSTR("Jog") : PSTR("Run");
    report_char('<');
    report_pstr(state);
    /* the executing block's line (as GRBL: only a positive one) is read
     * before the position, which the steppers only move further along that
     * line or past it: the position lies on or after its line's move. Read
     * after (the float formatting below takes ~1 ms), a block boundary
     * crossed in between named a line the position had not reached yet,
     * and a resume from that line left the pen's last steps out (~5 steps
     * at 3000 mm/min: tests/e2e/test_line_numbers.py) */
    plan_line_t ln = seg_exec_line();
    int32_t motor[N_AXIS], cart[N_AXIS];
    stepper_get_position(motor);
    plan_cart_from_motor(motor, cart);
    RPT("|MPos:");
    float mpos[GC_AXES] = {0};
    for (uint8_t a = 0; a < N_AXIS; a++)
        mpos[a] = (float)cart[a] / settings.steps_per_mm[a];
    report_xyz(mpos);
    if (settings.report_mask & 2) {
        RPT("|Bf:");
        report_uint(plan_free());
        report_char(',');
        report_uint(serial_rx_free());
    }
    if (ln) {
        RPT("|Ln:");
        report_uint(ln);
    }
    RPT("|FS:");
    report_uint((uint32_t)(stepper_busy() ? seg_speed() * 60.0f + 0.5f : 0));
    RPT(",0");
    if (in) {
        RPT("|Pn:");
        /* one letter per PIN_* bit, lowest first: X Y limits, R stop, H pause, S resume */
        for (uint8_t b = 0; b < 5; b++, in >>= 1)
            if (in & 1)
                serial_write(pgm_read_byte(PSTR("XYRHS") + b));
    }
    if (mach.pen_down)
        RPT("|A:S");
    /* WCO as GRBL refreshes it: after a change, then every 30th report
     * while busy and every 10th while idle */
    if (due(&mach.wco_countdown, busy ? 29 : 9)) {
        RPT("|WCO:");
        float wco[GC_AXES];
        for (uint8_t a = 0; a < GC_AXES; a++)
            wco[a] = gc_wco(&gc, a);
        report_xyz(wco);
    }
    /* Ov likewise: after a change, then every 20th report while busy, every 10th idle */
    if (due(&mach.ov_countdown, busy ? 19 : 9)) {
        RPT("|Ov:");
        for (uint8_t i = 0; i < 3; i++) {
            if (i)
                report_char(',');
            report_uint(rt_ov[i]);
        }
    }
    RPT(">\r\n");
}

void machine_pen_up_now(void)
{
    servo_set_us(settings.pen_up_us);
    mach.pen_down = mach.pen_lifted = mach.resuming = 0;
}

/* The servo toward the pen's new place at $64 (lower) / $65 (raise):
 * returns the milliseconds that takes. */
static uint16_t pen_servo(uint8_t down)
{
    uint16_t ms = down ? settings.pen_lower_ms : settings.pen_raise_ms;
    servo_move(down ? settings.pen_down_us : settings.pen_up_us, ms);
    return ms;
}

static void start_hold(void)
{
    if (mach.resuming) {
        /* held again while the pen goes back down: the hold stays, and the
         * pen-safe check in machine_poll lifts the pen once more */
        mach.resuming = 0;
        return;
    }
    if (!machine_moving() || mach.hold)
        return;
    mach.hold = 1;
    seg_hold(1);
    if (mach.jog)
        mach.jog_cancel = 1;
}

void machine_poll(void)
{
    wdt_reset();
    uint8_t f = realtime_take();
    uint8_t code = 0;
    if (f & RT_ALARM) {
        cli();
        code = rt_alarm;
        rt_alarm = 0;
        sei();
    }
    /* A reset raises ALARM:3 only when it stops the steppers (the receive
     * interrupt raised it then: a move or a hold still decelerating), as
     * GRBL's reset alarms only in a cycle or an executing hold. After a hold
     * has stopped, or with moves queued but not yet stepping, the position
     * is known: the queue is dropped and the board stays unlocked. */
    if (code) {
        machine_alarm(code);
        if (code == ALARM_ABORT_CYCLE)
            mach.homed = 0;
    }
    if (f & RT_RESET) {
        mach.reset = RESET_NOW;
        mach.abort = 1;
    }
    if (f & RT_OVERRIDE) {
        planner_set_overrides(rt_ov[OV_FEED], rt_ov[OV_RAPID]);
        mach.ov_countdown = 0;
    }
    if (f & RT_STATUS)
        machine_report_status();
    if (f & (RT_HOLD | RT_JOG_CANCEL)) {
        if (!(f & RT_HOLD) && !mach.jog)
            f &= (uint8_t)~RT_JOG_CANCEL;
        else
            start_hold();
    }
    if ((f & RT_RESUME) && mach.hold && !mach.jog_cancel && !mach.alarm && !mach.resuming) {
        /* the pen goes back down where it was lifted; motion waits out the
         * lowering and the settle */
        uint16_t ms = settings.pen_settle_ms;
        if (mach.pen_lifted)
            ms += pen_servo(1);
        mach.pen_lifted = 0;
        mach.resuming = 1;
        mach.resume_at = machine_ms() + ms;
    }
    if (mach.resuming && (int32_t)(machine_ms() - mach.resume_at) >= 0) {
        mach.resuming = 0;
        mach.hold = 0;
        seg_hold(0);
    }
    if (mach.alarm || mach.reset)
        return;
    /* a pen-safe hold: once stopped on the path, the pen leaves the paper */
    if (mach.hold && mach.pen_down && !mach.pen_lifted && !mach.resuming && !mach.jog &&
        hold_stopped()) {
        pen_servo(0);
        mach.pen_lifted = 1;
    }
    plan_override_step(); /* an override change's recompute, a slice per pass */
    seg_fill();
    if (!(mach.hold && seg_hold_reached() && seg_head == seg_tail))
        stepper_start();
    if (mach.jog_cancel && seg_hold_reached() && !stepper_busy()) {
        /* a cancelled jog forgets the rest of its moves */
        seg_drop_block();
        plan_reset();
        seg_reset();
        machine_resync();
        mach.hold = mach.jog_cancel = mach.jog = 0;
    }
    if (!machine_moving()) {
        mach.jog = 0;
        if (settings.idle_delay_ms != 255 && stepper_enabled() &&
            machine_ms() - idle_since >= settings.idle_delay_ms)
            stepper_enable(0);
    } else {
        idle_since = machine_ms();
    }
}

/* Let the main loop sleep until the next interrupt (UART, a step, the 1 ms
 * servo tick) when there is nothing to prepare: simavr then skips time. */
void machine_idle_wait(void)
{
    set_sleep_mode(SLEEP_MODE_IDLE);
    cli();
    if (!rt_flags && serial_tx_idle()) {
        sleep_enable();
        sei();
        sleep_cpu();
        sleep_disable();
    }
    sei();
}

uint8_t machine_sync(void)
{
    while (machine_moving() || (mach.hold && !mach.abort)) {
        machine_poll();
        if (mach.abort)
            return 0;
        machine_idle_wait();
    }
    return !mach.abort;
}

uint8_t machine_dwell_ms(uint32_t ms)
{
    if (!machine_sync())
        return 0;
    uint32_t start = machine_ms();
    mach.dwelling = 1;
    while (machine_ms() - start < ms) {
        machine_poll();
        if (mach.abort)
            break;
        machine_idle_wait();
    }
    mach.dwelling = 0;
    return !mach.abort;
}

void machine_pen(uint8_t down)
{
    if (mach.check)
        return;
    if (!machine_sync())
        return;
    if (down == mach.pen_down)
        return;
    mach.pen_down = down;
    machine_dwell_ms((uint32_t)pen_servo(down) + settings.pen_settle_ms);
}

/* Every line's soft-limit check (homing boards have them on): the tests
 * are integer compares of the floats' bits where they can be (a float
 * compare is ~50 cycles here, the add ~100): below -eps is a negative
 * float of greater magnitude, i.e. bits above -eps's as unsigned; the add
 * only past max travel (plan_lt: max travel is not negative). */
static uint8_t outside_work_area(const float *t)
{
    const uint32_t below = float_bits(-SOFT_LIMIT_EPS);
    for (uint8_t a = 0; a < N_AXIS; a++) {
        if (float_bits(t[a]) > below ||
            (plan_lt(settings.max_travel[a], t[a]) && t[a] > settings.max_travel[a] + SOFT_LIMIT_EPS))
            return 1;
    }
    return 0;
}

/* plan_line_split's wait: realtime work goes on while the planner is full.
 * No poll while there is room: on an idle machine the poll would take the
 * jog being queued for finished (nothing moving yet) and report it as Run. */
static uint8_t planner_room(void)
{
    while (!mach.abort && !plan_free()) {
        machine_poll();
        if (!mach.abort && !plan_free())
            machine_idle_wait();
    }
    return !mach.abort;
}

/* Queue one straight move (in pieces if it is long), waiting for planner room. */
static uint8_t line_to(const float *target, float feed, uint8_t flags)
{
    if (mach.check)
        return STATUS_OK;
    uint8_t queued = plan_line_split(target, feed, flags, planner_room);
    if (!stepper_busy()) /* (running, they are fed by the main loop's next poll) */
        machine_poll(); /* the steppers start before the line's ok */
    return queued && !mach.abort ? STATUS_OK : ERR_LOCKED;
}

static uint8_t soft_limit_violation(const gc_block_t *blk)
{
    if (!settings.soft_limits)
        return 0;
    if (blk->action == ACT_G28)
        return blk->has_via && outside_work_area(blk->via);
    if (blk->action == ACT_RAPID || blk->action == ACT_LINE)
        return outside_work_area(blk->target);
    if (blk->action == ACT_ARC) {
        /* the arc's bounding box: its ends, plus each axis extreme it sweeps */
        arc_t arc;
        if (arc_init(&arc, blk->start, blk->target, blk->center, blk->clockwise, settings.arc_tolerance))
            return 1;
        if (outside_work_area(blk->target))
            return 1;
        /* the axis extremes it passes: the quarter turns b * pi/2 between its
         * end angles (b + 8 counted from floor(angle / (pi/2)) + 8: positive
         * before the truncation), each at r along +X, +Y, -X or -Y (b % 4) */
        float r = arc.r0 > arc.r1 ? arc.r0 : arc.r1;
        int8_t i0 = (int8_t)(arc.angle0 * (float)M_2_PI + 8.0f);
        int8_t i1 = (int8_t)((arc.angle0 + arc.sweep) * (float)M_2_PI + 8.0f);
        int8_t hi = i0 > i1 ? i0 : i1;
        for (int8_t b = (int8_t)((i0 > i1 ? i1 : i0) + 1); b <= hi; b++) {
            float p[N_AXIS] = {arc.center[0], arc.center[1]};
            float d = b & 2 ? -r : r;
            if (b & 1)
                p[1] += d;
            else
                p[0] += d;
            if (outside_work_area(p))
                return 1;
        }
    }
    return 0;
}

uint8_t machine_execute(const gc_block_t *blk)
{
    if (blk->motors == MOTORS_ON && !mach.check)
        stepper_enable(1);
    if (blk->pen != PEN_KEEP)
        machine_pen(blk->pen == PEN_DOWN);
    if (mach.abort)
        return ERR_LOCKED;
    plan_set_line_number(blk->line);
    if (blk->dwell && !mach.check) /* G4: before a motion on its line */
        machine_dwell_ms((uint32_t)(blk->dwell_s * 1000.0f + 0.5f));
    uint8_t e = STATUS_OK;
    switch (blk->action) {
    case ACT_RAPID: e = line_to(blk->target, 0.0f, PB_RAPID); break;
    case ACT_LINE: {
        float feed = blk->feed;
#if GRBL_G93
        /* G93: F is how many times a minute this move could be done */
        if (blk->inverse_time) {
            float dx = blk->target[0] - blk->start[0], dy = blk->target[1] - blk->start[1];
            feed *= sqrtf(dx * dx + dy * dy);
        }
#endif
        e = line_to(blk->target, feed, 0);
        break;
    }
    case ACT_ARC: {
        arc_t arc;
        e = arc_init(&arc, blk->start, blk->target, blk->center, blk->clockwise, settings.arc_tolerance);
        float feed = blk->feed;
#if GRBL_G93
        if (blk->inverse_time)
            feed *= fabsf(arc.sweep) * 0.5f * (arc.r0 + arc.r1);
#endif
        /* check mode queues nothing: the chords would only starve the watchdog */
        for (uint16_t k = 1; !e && !mach.check && k <= arc.segments; k++) {
            float p[N_AXIS];
            arc_point(&arc, k, p);
            e = line_to(p, feed, 0);
        }
        break;
    }
    case ACT_G28:
        if (blk->has_via)
            e = line_to(blk->via, 0.0f, PB_RAPID);
        if (!e)
            e = line_to(blk->target, 0.0f, PB_RAPID);
        break;
    default: break;
    }
    if (!e && blk->program_end) {
        machine_pen(0);
        report_msg(PSTR("Pgm End"));
    }
    if (!e && blk->pause && !mach.check && machine_sync()) {
        /* M0: a feed hold at this point of the program (Hold:0); its ok
         * comes when ~ resumes, as GRBL suspends inside the line */
        mach.hold = 1;
        seg_hold(1);
        machine_sync();
    }
    if (blk->wco_changed)
        mach.wco_countdown = 0;
    /* EEPROM writes stall the CPU: after the queued motion, as GRBL does;
     * never in check mode (nothing there writes EEPROM) */
    if (!e && blk->store_slot && !mach.check && machine_sync())
        coord_save((uint8_t)(blk->store_slot - 1), blk->store);
    if (!e && blk->motors == MOTORS_OFF && !mach.check && machine_sync())
        stepper_enable(0);
    if (mach.abort)
        return ERR_LOCKED;
    return e;
}

uint8_t machine_check_limits(const gc_block_t *blk)
{
    if (mach.check || !soft_limit_violation(blk))
        return 0;
    /* the moves before it are valid: let them finish, then lock */
    if (machine_sync())
        machine_alarm(ALARM_SOFT_LIMIT);
    return 1;
}

uint8_t machine_jog(const char *body)
{
    gc_state_t tmp = gc, undo; /* a jog changes no modal state: only pos is kept */
    gc_block_t blk;
    uint8_t e = gc_parse(body, &tmp, &blk, 1, &undo);
    if (e)
        return e;
    if (settings.soft_limits && outside_work_area(blk.target))
        return ERR_TRAVEL_EXCEEDED;
    if (mach.check)
        return STATUS_OK;
    if (blk.pen != PEN_KEEP) /* its Z moves the pen, as a G1's does */
        machine_pen(blk.pen == PEN_DOWN);
    mach.jog = 1;
    /* where it ends, pos and machine Z (side by side in the state) */
    _Static_assert(offsetof(gc_state_t, z) == offsetof(gc_state_t, pos) + sizeof(gc.pos), "pos, z");
    memcpy(gc.pos, tmp.pos, sizeof(gc.pos) + sizeof(gc.z));
    plan_set_line_number(blk.line);
    return line_to(blk.target, blk.feed, PB_JOG);
}
