/* plotbridge firmware: GRBL 1.1 compatible pen plotter on an ATmega328P. */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/wdt.h>
#include "inputs.h"
#include "machine.h"
#include "protocol.h"
#include "report.h"
#include "serial.h"
#include "servo.h"
#include "settings.h"
#include "status.h"
#include "stepper.h"

/* A watchdog reset leaves the watchdog running at its shortest period:
 * turn it off before anything else, or the chip resets forever. */
void wdt_off_early(void) __attribute__((naked, used, section(".init3")));
void wdt_off_early(void)
{
    MCUSR = 0;
    wdt_disable();
}

int main(void)
{
    uint8_t settings_ok = settings_load();
    serial_init();
    inputs_init();
    stepper_init();
    servo_init();
    servo_set_us(settings.pen_up_us);
    machine_init();
    wdt_enable(WDTO_1S);
    sei();
    report_banner();
    if (!settings_ok)
        report_msg(PSTR("Settings restored to defaults"));
    if (settings.homing_enable) {
        mach.alarm = ALARM_LOCKED;
        report_unlock_hint();
    }
    if (inputs_read() & PIN_ESTOP) {
        mach.alarm = ALARM_ESTOP;
        report_alarm(ALARM_ESTOP);
    }
    protocol_run();
    return 0;
}
