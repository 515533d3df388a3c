#include "dollar.h"
#include "homing.h"
#include "inputs.h"
#include "machine.h"
#include "numparse.h"
#include "planner.h"
#include "protocol.h"
#include "report.h"
#include "settings.h"
#include "status.h"
#include "stepper.h"

static void print_settings(void)
{
    for (uint8_t i = 0; i < settings_count; i++) {
        uint8_t id = settings_id(i);
        float v = 0.0f;
        settings_get(&settings, id, &v);
        report_char('$');
        report_uint(id);
        report_char('=');
        report_fixed(v, settings_is_integer(id) ? 0 : 3);
        RPT("\r\n");
    }
}

static void print_modes(void)
{
    RPT("[GC:G");
    report_uint(gc.motion == MOTION_NONE ? 80 : gc.motion);
    RPT(" G");
#if GRBL_WCS
    report_uint(54 + gc.coord);
#else
    RPT("54");
#endif
    RPT(" G");
    report_uint(17 + gc.plane);
    report_pstr(gc.inches ? PSTR(" G20") : PSTR(" G21"));
    report_pstr(gc.incremental ? PSTR(" G91") : PSTR(" G90"));
#if GRBL_G93
    report_pstr(gc.inverse_time ? PSTR(" G93 ") : PSTR(" G94 "));
#else
    RPT(" G94 ");
#endif
    report_pstr(mach.pen_down ? PSTR("M3") : PSTR("M5"));
    RPT(" M9 T0 F");
    report_fixed(gc.feed, 0);
    RPT(" S0]\r\n");
}

/* $#: G54..G59, G28, G30 (stored; zeros without GRBL_WCS), G92, TLO, PRB */
static void print_offsets(void)
{
    for (uint8_t i = 0; i < GC_SLOTS; i++) {
        float v[GC_AXES] = {0};
#if GRBL_WCS
        coord_load(i, v);
#endif
        RPT("[G");
        report_uint(i < GC_SLOT_G28 ? 54 + i : i == GC_SLOT_G28 ? 28 : 30);
        report_char(':');
        report_xyz(v);
        RPT("]\r\n");
    }
    RPT("[G92:");
    report_xyz(gc.g92);
    RPT("]\r\n[TLO:0.000]\r\n[PRB:0.000,0.000,0.000:0]\r\n");
}

#if GRBL_LINES
/* $N0=line, $N1=line: checked by running it once, as GRBL does (Idle only) */
static uint8_t store_startup_line(const char *arg)
{
    uint8_t n = (uint8_t)(arg[1] - '0');
    if (n >= EELINE_STARTUP_COUNT || arg[2] != '=')
        return ERR_INVALID_DOLLAR;
    if (mach.alarm || mach.check || machine_moving())
        return ERR_NOT_IDLE;
    uint8_t e = protocol_gcode(arg + 3);
    if (!e)
        eeline_save(n, arg + 3);
    return e;
}

static void print_startup_lines(void)
{
    char line[LINE_SIZE + 1];
    for (uint8_t n = 0; n < EELINE_STARTUP_COUNT; n++) {
        eeline_load(n, line);
        RPT("$N");
        report_uint(n);
        report_char('=');
        report_str(line);
        RPT("\r\n");
    }
}
#endif

static void print_build_info(void)
{
    RPT(FW_VERSION);
#if GRBL_LINES
    char info[LINE_SIZE + 1];
    eeline_load(EELINE_BUILD_INFO, info);
    report_str(info);
#endif
    /* GRBL's letters, in its order: N (line numbers, every board has them),
     * then what this build leaves out */
    RPT("]\r\n[OPT:N"
#if !GRBL_WCS
        "#"
#endif
#if !GRBL_LINES
        "I"
#endif
        ",");
    report_uint(PLAN_SIZE - 1); /* the same count as Bf: when idle */
    RPT(",128]\r\n");
}

/* $RST=$ settings, $RST=# stored positions, $RST=* all; then a reset */
static uint8_t restore(const char *arg)
{
    uint8_t what = arg[4] == '$' ? RESTORE_SETTINGS : arg[4] == '*' ? RESTORE_ALL : 0;
#if GRBL_WCS
    if (arg[4] == '#')
        what = RESTORE_COORDS;
#endif
    if (arg[0] != 'R' || arg[1] != 'S' || arg[2] != 'T' || arg[3] != '=' || !what || arg[5])
        return ERR_INVALID_DOLLAR;
    if (machine_moving())
        return ERR_NOT_IDLE;
    settings_restore(what);
    stepper_apply_settings();
    report_msg(PSTR("Restoring defaults"));
    mach.reset = RESET_AFTER_ACK;
    mach.abort = 1;
    return STATUS_OK;
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
        RPT("[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]\r\n");
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
    if (arg[0] == 'R')
        return restore(arg);
#if GRBL_LINES
    if (arg[0] == 'N' && arg[1])
        return store_startup_line(arg);
    if (arg[0] == 'I' && arg[1] == '=') {
        if (machine_moving())
            return ERR_NOT_IDLE;
        eeline_save(EELINE_BUILD_INFO, arg + 2);
        return STATUS_OK;
    }
#endif
    if (arg[0] == 'S' && arg[1] == 'L' && arg[2] == 'P' && !arg[3]) {
        /* sleep after the ok: pen up, motors off, only a reset wakes it */
        if (machine_moving())
            return ERR_NOT_IDLE;
        mach.sleep = 1;
        return STATUS_OK;
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
        print_build_info();
        return STATUS_OK;
#if GRBL_LINES
    case 'N':
        print_startup_lines();
        return STATUS_OK;
#endif
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
        protocol_startup_lines(); /* as GRBL: after a successful homing cycle */
        return STATUS_OK;
    }
    default: return ERR_INVALID_DOLLAR;
    }
}
