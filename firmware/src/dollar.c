#include "dollar.h"
#include "homing.h"
#include "inputs.h"
#include "machine.h"
#include "numparse.h"
#include "planner.h"
#include "report.h"
#include "settings.h"
#include "status.h"
#include "stepper.h"

static void print_settings(void)
{
    for (uint8_t i = 0; i < settings_count; i++) {
        uint8_t id = settings_ids[i];
        float v = 0.0f;
        settings_get(&settings, id, &v);
        RPT("$");
        report_uint(id);
        RPT("=");
        report_fixed(v, settings_is_integer(id) ? 0 : 3);
        RPT("\r\n");
    }
}

static void print_modes(void)
{
    RPT("[GC:G");
    report_uint(gc.motion == MOTION_NONE ? 80 : gc.motion);
    RPT(" G54 G");
    report_uint(17 + gc.plane);
    report_pstr(gc.inches ? PSTR(" G20") : PSTR(" G21"));
    report_pstr(gc.incremental ? PSTR(" G91") : PSTR(" G90"));
    RPT(" G94 ");
    report_pstr(mach.pen_down ? PSTR("M3") : PSTR("M5"));
    RPT(" M9 T0 F");
    report_fixed(gc.feed, 0);
    RPT(" S0]\r\n");
}

static void print_offsets(void)
{
    const char *const labels[] = {PSTR("G54"), PSTR("G28"), PSTR("G30")};
    for (uint8_t i = 0; i < 3; i++) {
        RPT("[");
        report_pstr(labels[i]);
        RPT(":0.000,0.000,0.000]\r\n");
    }
    RPT("[G92:");
    report_fixed(gc.offset[0], 3);
    RPT(",");
    report_fixed(gc.offset[1], 3);
    RPT(",");
    report_fixed(gc.z_offset, 3);
    RPT("]\r\n[TLO:0.000]\r\n");
}

static uint8_t set_setting(const char *line)
{
    uint8_t i = 1;
    float id_f, value;
    if (!read_number(line, &i, &id_f) || line[i] != '=' || id_f < 0.0f || id_f > 255.0f ||
        id_f != (float)(uint8_t)id_f)
        return ERR_INVALID_DOLLAR;
    i++;
    if (!read_number(line, &i, &value) || line[i])
        return ERR_BAD_NUMBER;
    if (machine_moving())
        return ERR_NOT_IDLE;
    uint8_t e = settings_set(&settings, (uint8_t)id_f, value);
    if (e)
        return e;
    settings_save();
    stepper_apply_settings();
    if (id_f >= 100.0f && id_f <= 101.0f) /* a new scale moves the planner's idea of where we are */
        machine_resync();
    return STATUS_OK;
}

uint8_t dollar_execute(const char *line)
{
    const char *arg = line + 1;
    if (arg[0] == 0) {
        RPT("[HLP:$$ $# $G $I $x=val $J=line $C $X $H ~ ! ? ctrl-x]\r\n");
        return STATUS_OK;
    }
    if (arg[0] == 'J' && arg[1] == '=') {
        if (mach.alarm)
            return ERR_LOCKED;
        if (machine_moving() && !mach.jog)
            return ERR_NOT_IDLE;
        return machine_jog(arg + 2);
    }
    if (arg[0] >= '0' && arg[0] <= '9') {
        if (mach.homing)
            return ERR_NOT_IDLE;
        return set_setting(line);
    }
    if (arg[1] != 0)
        return ERR_INVALID_DOLLAR;
    switch (arg[0]) {
    case '$':
        print_settings();
        return STATUS_OK;
    case 'G':
        print_modes();
        return STATUS_OK;
    case '#':
        print_offsets();
        return STATUS_OK;
    case 'I':
        RPT(FW_BUILD "\r\n[OPT:,");
        report_uint(PLAN_SIZE - 1); /* the same count as Bf: when idle */
        RPT(",128]\r\n");
        return STATUS_OK;
    case 'X':
        if (inputs_read() & PIN_ESTOP)
            return ERR_LOCKED; /* the stop button is still pressed */
        if (mach.alarm) {
            report_msg(PSTR("Caution: Unlocked"));
            mach.alarm = 0;
            inputs_led(0);
        }
        return STATUS_OK;
    case 'C':
        if (machine_moving() || (mach.alarm && !mach.check))
            return ERR_NOT_IDLE;
        if (mach.check) {
            /* leaving the dry run resets, as GRBL does, so no parsed state lingers */
            mach.check = 0;
            report_msg(PSTR("Disabled"));
            mach.reset = RESET_AFTER_ACK;
            mach.abort = 1;
        } else {
            mach.check = 1;
            report_msg(PSTR("Enabled"));
        }
        return STATUS_OK;
    case 'H': {
        if (!settings.homing_enable)
            return ERR_HOMING_DISABLED;
        if (mach.check || machine_moving())
            return ERR_NOT_IDLE;
        if (inputs_read() & PIN_ESTOP)
            return ERR_LOCKED;
        mach.alarm = 0;
        inputs_led(0);
        uint8_t code = homing_run();
        if (code) {
            machine_alarm(code);
            return ERR_LOCKED;
        }
        mach.homed = 1;
        machine_resync();
        return STATUS_OK;
    }
    default: return ERR_INVALID_DOLLAR;
    }
}
