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
    RPT(" M");
    report_char(gc.coolant ? '8' : '9');
    RPT(" T0 F");
    report_fixed(gc.feed, 0);
    RPT(" S");
    report_fixed(gc.spindle, 0);
    RPT("]\r\n");
}

/* $#: G54..G59, G28, G30 (stored; without GRBL_WCS only G54, the rest zeros), G92, TLO, PRB */
static void print_offsets(void)
{
    for (uint8_t i = 0; i < GC_SLOTS; i++) {
        float v[GC_AXES] = {0};
        if (GRBL_WCS || !i) /* (the 328P stores G54 only) */
            coord_load(i, v);
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
    uint8_t what = arg[4] == '$' ? RESTORE_SETTINGS : arg[4] == '*' ? RESTORE_ALL :
                   arg[4] == '#' ? RESTORE_COORDS : 0;
    if (arg[1] != 'S' || arg[2] != 'T' || arg[3] != '=' || !what || arg[5])
        return ERR_INVALID_DOLLAR;
    settings_restore(what);
    stepper_apply_settings();
    report_msg(PSTR("Restoring defaults"));
    mach.reset = RESET_AFTER_ACK;
    mach.abort = 1;
    return STATUS_OK;
}

/* $x=val, in GRBL's order: a bad number is error:2, anything else wrong 3 */
static uint8_t set_setting(const char *line)
{
    uint8_t i = 1;
    float id_f, value;
    if (!read_number(line, &i, &id_f))
        return ERR_BAD_NUMBER;
    if (line[i++] != '=')
        return ERR_INVALID_DOLLAR;
    if (!read_number(line, &i, &value))
        return ERR_BAD_NUMBER;
    if (line[i] || id_f < 0.0f || id_f > 255.0f)
        return ERR_INVALID_DOLLAR;
    uint8_t id = (uint8_t)id_f; /* (GRBL truncates the number) */
    uint8_t e = settings_set(&settings, id, value);
    if (e)
        return e;
    settings_save();
    stepper_apply_settings();
    plan_settings_changed();
    if (id >= 100 && id <= 101) /* a new scale moves the planner's idea of where we are */
        machine_resync();
    return STATUS_OK;
}

/* GRBL's dispatch: $J= in Idle or Jog; $$ $G $C $X anywhere (one letter);
 * everything else (EEPROM, homing, sleep, $#, $I) only in Idle or Alarm,
 * so check mode answers it error:8: nothing there writes EEPROM, sleeps or
 * resets, and only $C leaves it. */
uint8_t dollar_execute(const char *line)
{
    const char *arg = line + 1;
    char c = arg[0];
    if (c == 0) {
        RPT("[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]\r\n");
        return STATUS_OK;
    }
    if (c == 'J') {
        if (mach.alarm || mach.check || mach.homing || (machine_moving() && !mach.jog))
            return ERR_NOT_IDLE;
        if (arg[1] != '=')
            return ERR_INVALID_DOLLAR;
        return machine_jog(arg + 2);
    }
    if (c == '$' || c == 'G' || c == 'C' || c == 'X') {
        if (arg[1] != 0)
            return ERR_INVALID_DOLLAR;
        if (c == '$')
            print_settings();
        else if (c == 'G')
            print_modes();
        else if (c == 'X') {
            if (inputs_read() & PIN_ESTOP)
                return ERR_LOCKED; /* the stop button is still pressed */
            if (mach.alarm) {
                report_msg(PSTR("Caution: Unlocked"));
                mach.alarm = 0;
                inputs_led(0);
            }
        } else if (mach.check) {
            /* leaving the dry run resets, as GRBL does, so no parsed state lingers */
            mach.check = 0;
            report_msg(PSTR("Disabled"));
            mach.reset = RESET_AFTER_ACK;
            mach.abort = 1;
        } else {
            if (machine_moving() || mach.alarm || mach.hold)
                return ERR_NOT_IDLE;
            mach.check = 1;
            report_msg(PSTR("Enabled"));
        }
        return STATUS_OK;
    }
    if (mach.check || mach.homing || mach.hold || machine_moving())
        return ERR_NOT_IDLE;
    switch (c) {
    case '#':
        if (arg[1])
            return ERR_INVALID_DOLLAR;
        print_offsets();
        return STATUS_OK;
    case 'S':
        if (arg[1] != 'L' || arg[2] != 'P' || arg[3])
            return ERR_INVALID_DOLLAR;
        mach.sleep = 1; /* after the ok: pen up, motors off, only a reset wakes it */
        return STATUS_OK;
    case 'R':
        return restore(arg);
    case 'I':
        if (!arg[1]) {
            print_build_info();
            return STATUS_OK;
        }
#if GRBL_LINES
        if (arg[1] != '=')
            return ERR_INVALID_DOLLAR;
        eeline_save(EELINE_BUILD_INFO, arg + 2);
        return STATUS_OK;
#else
        return ERR_INVALID_DOLLAR;
#endif
    case 'N':
#if GRBL_LINES
        if (!arg[1]) {
            print_startup_lines();
            return STATUS_OK;
        }
        return store_startup_line(arg);
#else
        return ERR_INVALID_DOLLAR;
#endif
    case 'H': {
        if (arg[1])
            return ERR_INVALID_DOLLAR;
        if (!settings.homing_enable)
            return ERR_HOMING_DISABLED;
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
    default: return set_setting(line);
    }
}
