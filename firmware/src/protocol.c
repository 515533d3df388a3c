#include <avr/interrupt.h>
#include <avr/sleep.h>
#include "dollar.h"
#include "gcode.h"
#include "inputs.h"
#include "linebuf.h"
#include "machine.h"
#include "planner.h"
#include "protocol.h"
#include "realtime.h"
#include "report.h"
#include "segment.h"
#include "serial.h"
#include "servo.h"
#include "settings.h"
#include "status.h"
#include "stepper.h"

static linebuf_t lb;

uint8_t protocol_gcode(const char *line)
{
    /* G-code is locked in Alarm and while a jog runs (GRBL: error:9) */
    if (mach.alarm || (mach.jog && machine_moving()))
        return ERR_LOCKED;
    /* parsed in place, put back when the line is bad or refused (gcode.h) */
    gc_state_t undo;
    gc_block_t blk;
    uint8_t e = gc_parse(line, &gc, &blk, 0, &undo);
    uint8_t refused = !e && machine_check_limits(&blk);
    if (e || refused) {
        gc_undo(&gc, &undo, &blk);
        if (refused) { /* (soft limits) */
            machine_resync();
            e = ERR_LOCKED;
        }
        return e;
    }
    return machine_execute(&blk);
}

static uint8_t execute_line(const char *line)
{
    if (line[0] == 0 || (line[0] == '%' && line[1] == 0)) /* '%' program delimiters: ignored */
        return STATUS_OK;
    if (line[0] == '$')
        return dollar_execute(line);
    return protocol_gcode(line);
}

void protocol_startup_lines(void)
{
#if GRBL_LINES
    /* the line buffer is free here (after a reset, or $H's line is done) */
    for (uint8_t n = 0; n < EELINE_STARTUP_COUNT; n++) {
        uint8_t ok = eeline_load(n, lb.text);
        if (ok && !lb.text[0])
            continue;
        report_char('>');
        report_str(lb.text);
        report_char(':');
        report_status_code(ok ? protocol_gcode(lb.text) : ERR_EEPROM_READ);
    }
    lb.text[0] = 0;
#endif
}

/* Soft reset: motion is already stopped (in the interrupt that saw 0x18);
 * everything queued is forgotten, the position is kept. */
static void soft_reset(void)
{
    stepper_halt();
    serial_rx_flush();
    linebuf_reset(&lb);
    uint8_t alarm = mach.alarm;
    uint8_t homed = mach.homed;
    machine_init();
    if (mach.sleep)
        alarm = ALARM_LOCKED; /* GRBL wakes from sleep locked */
    mach.sleep = mach.abort = mach.reset = mach.hold = mach.jog = mach.jog_cancel = mach.check = 0;
    mach.dwelling = 0;
    seg_hold(0);
    mach.alarm = alarm;
    mach.homed = homed;
    machine_pen_up_now(); /* as GRBL stops the spindle on every reset */
    mach.wco_countdown = mach.ov_countdown = 0;
    /* overrides back to 100% on every reset, as GRBL */
    rt_ov[OV_FEED] = rt_ov[OV_RAPID] = rt_ov[OV_SPINDLE] = 100;
    planner_set_overrides(100, 100);
    report_banner();
    if (mach.alarm)
        report_unlock_hint();
    else
        protocol_startup_lines();
}

/* Idle with part of a line in (or none): sleep on through the receive
 * interrupts of its bytes (a machine_poll after each cost more than parsing
 * the line) until the receive interrupt has a line end or half a ring, a
 * realtime request comes, or the 1 ms clock ticks (machine_poll's timed
 * work: the $1 motor delay, a resume's settle; and the watchdog). A sender
 * that stops half way through a line thus only slows polling to 1 kHz. */
static void wait_for_line(void)
{
    uint8_t tick = (uint8_t)timebase_ms();
    set_sleep_mode(SLEEP_MODE_IDLE);
    for (;;) {
        cli();
        if (serial_rx_wake || rt_flags || (uint8_t)timebase_ms() != tick)
            break;
        sleep_enable();
        sei(); /* (the instruction after sei still runs first: no wake-up is missed) */
        sleep_cpu();
        sleep_disable();
    }
    sei();
}

void protocol_run(void)
{
    linebuf_reset(&lb);
    if (!mach.alarm)
        protocol_startup_lines();
    for (;;) {
        machine_poll();
        if (mach.reset) {
            soft_reset();
            continue;
        }
        if (mach.sleep) {
            /* $SLP: lines wait in the receive ring until a reset flushes them */
            if (mach.sleep == 1) {
                mach.sleep = 2;
                machine_pen_up_now();
                stepper_enable(0);
                report_msg(PSTR("Sleeping"));
            }
            machine_idle_wait();
            continue;
        }
        if (mach.abort && !machine_moving())
            mach.abort = 0;
        /* a whole line between polls: polling per byte cost more than parsing */
        serial_rx_wake = 0;
        uint8_t r = serial_read_line(&lb);
        if (r == LB_NONE) {
            if (!machine_moving())
                wait_for_line();
            continue;
        }
        uint8_t e;
        if (r == LB_OVERFLOW)
            e = ERR_OVERFLOW;
        else if (r == LB_BAD_BYTE)
            e = ERR_EXPECTED_LETTER;
        else
            e = execute_line(lb.text);
        if (mach.reset == RESET_NOW)
            continue; /* a reset flushed the line: no acknowledgement */
        report_status_code(e);
    }
}
