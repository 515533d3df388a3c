/* Switches and buttons of the board header, all to ground with pull-ups.
 * A board has per axis either one switch (X_LIMIT: at the homing end) or
 * min and max switches (X_MIN, X_MAX), or none; buttons are optional.
 * Boards that define INPUTS_PCINT act on pin-change interrupts (the Uno
 * shield: port B switches on PCINT0, port C buttons on PCINT1); the others
 * are sampled from the 1 ms servo timer interrupt (inputs_poll), which stops
 * a hard-limit hit within 1 ms wherever the pins sit on the Mega. */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <util/atomic.h>
#include "config.h"
#include "inputs.h"
#include "realtime.h"
#include "settings.h"
#include "status.h"

static volatile uint8_t homing;

#define PULLUP(pin) IO_INPUT_PULLUP(pin)
#define CLOSED(pin) (!IO_READ(pin)) /* a closed switch or pressed button pulls low */

void inputs_init(void)
{
#ifdef X_LIMIT
    PULLUP(X_LIMIT);
    PULLUP(Y_LIMIT);
#endif
#ifdef X_MIN
    PULLUP(X_MIN);
    PULLUP(X_MAX);
    PULLUP(Y_MIN);
    PULLUP(Y_MAX);
#endif
#ifdef BUTTON_ESTOP
    PULLUP(BUTTON_ESTOP);
#endif
#ifdef BUTTON_PAUSE
    PULLUP(BUTTON_PAUSE);
#endif
#ifdef BUTTON_RESUME
    PULLUP(BUTTON_RESUME);
#endif
#ifdef LED_STOP
    IO_OUTPUT(LED_STOP);
#endif
#ifdef INPUTS_PCINT
    PCMSK0 = IO_MASK(X_LIMIT) | IO_MASK(Y_LIMIT);
    PCMSK1 = IO_MASK(BUTTON_ESTOP) | IO_MASK(BUTTON_PAUSE) | IO_MASK(BUTTON_RESUME);
    PCIFR = (1 << PCIF0) | (1 << PCIF1);
    PCICR = (1 << PCIE0) | (1 << PCIE1);
#endif
}

/* per axis: any of its switches closed */
uint8_t inputs_limits(void)
{
    uint8_t r = 0;
#ifdef X_LIMIT
    if (CLOSED(X_LIMIT))
        r |= PIN_X_LIMIT;
    if (CLOSED(Y_LIMIT))
        r |= PIN_Y_LIMIT;
#endif
#ifdef X_MIN
    if (CLOSED(X_MIN) || CLOSED(X_MAX))
        r |= PIN_X_LIMIT;
    if (CLOSED(Y_MIN) || CLOSED(Y_MAX))
        r |= PIN_Y_LIMIT;
#endif
    return r ^ (settings.limit_invert & 3);
}

/* per axis: the switch at the homing end ($23) closed */
uint8_t inputs_home_switches(void)
{
#ifdef X_MIN
    uint8_t to_min = settings.homing_dir_mask;
    uint8_t r = 0;
    if (CLOSED(X_MIN) && (to_min & 1))
        r |= PIN_X_LIMIT;
    if (CLOSED(X_MAX) && !(to_min & 1))
        r |= PIN_X_LIMIT;
    if (CLOSED(Y_MIN) && (to_min & 2))
        r |= PIN_Y_LIMIT;
    if (CLOSED(Y_MAX) && !(to_min & 2))
        r |= PIN_Y_LIMIT;
    return r ^ (settings.limit_invert & 3);
#else
    return inputs_limits();
#endif
}

uint8_t inputs_read(void)
{
    uint8_t r = inputs_limits();
#ifdef BUTTON_ESTOP
    if (CLOSED(BUTTON_ESTOP))
        r |= PIN_ESTOP;
#endif
#ifdef BUTTON_PAUSE
    if (CLOSED(BUTTON_PAUSE))
        r |= PIN_PAUSE;
#endif
#ifdef BUTTON_RESUME
    if (CLOSED(BUTTON_RESUME))
        r |= PIN_RESUME;
#endif
    return r;
}

void inputs_homing(uint8_t on) { homing = on; }

void inputs_led(uint8_t on)
{
#ifdef LED_STOP
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { IO_SET(LED_STOP, on); }
#else
    (void)on;
#endif
}

/* interrupt context: a limit closing stops within this step period; stop
 * acts here and now; pause and resume go through the main loop */
static void inputs_changed(void)
{
    uint8_t in = inputs_read();
    if ((in & (PIN_X_LIMIT | PIN_Y_LIMIT)) && !homing && settings.hard_limits)
        realtime_alarm_isr(ALARM_HARD_LIMIT);
    if (in & PIN_ESTOP) {
        realtime_alarm_isr(ALARM_ESTOP);
        inputs_led(1);
    }
    if (in & PIN_PAUSE)
        rt_flags |= RT_HOLD;
    if (in & PIN_RESUME)
        rt_flags |= RT_RESUME;
}

#ifdef INPUTS_PCINT
ISR(PCINT0_vect) { inputs_changed(); }
ISR(PCINT1_vect, ISR_ALIASOF(PCINT0_vect));
#else
/* from the servo timer interrupt: act on a change only (about 30 cycles) */
void inputs_poll(void)
{
    static uint8_t last_in;
    uint8_t in = inputs_read();
    if (in != last_in) {
        last_in = in;
        if (in)
            inputs_changed();
    }
}
#endif
