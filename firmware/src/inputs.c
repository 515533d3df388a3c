#include <avr/interrupt.h>
#include <avr/io.h>
#include "config.h"
#include "inputs.h"
#include "realtime.h"
#include "settings.h"
#include "status.h"

static volatile uint8_t homing;

void inputs_init(void)
{
    IO_INPUT_PULLUP(X_LIMIT);
    IO_INPUT_PULLUP(Y_LIMIT);
    IO_INPUT_PULLUP(BUTTON_ESTOP);
    IO_INPUT_PULLUP(BUTTON_PAUSE);
    IO_INPUT_PULLUP(BUTTON_RESUME);
    IO_OUTPUT(LED_STOP);
    PCMSK0 = IO_MASK(X_LIMIT) | IO_MASK(Y_LIMIT); /* PCINT1, PCINT2 */
    PCMSK1 = IO_MASK(BUTTON_ESTOP) | IO_MASK(BUTTON_PAUSE) | IO_MASK(BUTTON_RESUME); /* PCINT8..10 */
    PCIFR = (1 << PCIF0) | (1 << PCIF1);
    PCICR = (1 << PCIE0) | (1 << PCIE1);
}

uint8_t inputs_limits(void)
{
    uint8_t r = 0; /* a closed switch pulls low */
    if (!IO_READ(X_LIMIT))
        r |= PIN_X_LIMIT;
    if (!IO_READ(Y_LIMIT))
        r |= PIN_Y_LIMIT;
    return r ^ (settings.limit_invert & 3);
}

uint8_t inputs_read(void)
{
    uint8_t r = inputs_limits();
    if (!IO_READ(BUTTON_ESTOP))
        r |= PIN_ESTOP;
    if (!IO_READ(BUTTON_PAUSE))
        r |= PIN_PAUSE;
    if (!IO_READ(BUTTON_RESUME))
        r |= PIN_RESUME;
    return r;
}

void inputs_homing(uint8_t on) { homing = on; }

void inputs_led(uint8_t on)
{
    IO_SET(LED_STOP, on);
}

/* a limit closing: stop within this step period */
ISR(PCINT0_vect)
{
    if (!homing && settings.hard_limits && inputs_limits())
        realtime_alarm_isr(ALARM_HARD_LIMIT);
}

/* buttons: stop acts here and now; pause and resume go through the main loop */
ISR(PCINT1_vect)
{
    uint8_t in = inputs_read();
    if (in & PIN_ESTOP) {
        realtime_alarm_isr(ALARM_ESTOP);
        inputs_led(1);
    }
    if (in & PIN_PAUSE)
        rt_flags |= RT_HOLD;
    if (in & PIN_RESUME)
        rt_flags |= RT_RESUME;
}
