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
    DDRB &= ~LIMIT_MASK;
    PORTB |= LIMIT_MASK;
    DDRC &= ~BUTTON_MASK;
    PORTC |= BUTTON_MASK;
    DDRC |= 1 << LED_BIT;
    PCMSK0 = LIMIT_MASK;   /* PCINT1, PCINT2 */
    PCMSK1 = BUTTON_MASK;  /* PCINT8..10 */
    PCIFR = (1 << PCIF0) | (1 << PCIF1);
    PCICR = (1 << PCIE0) | (1 << PCIE1);
}

uint8_t inputs_limits(void)
{
    uint8_t raw = (uint8_t)(~PINB); /* closed switch pulls low */
    uint8_t r = 0;
    if (raw & (1 << X_LIMIT_BIT))
        r |= PIN_X_LIMIT;
    if (raw & (1 << Y_LIMIT_BIT))
        r |= PIN_Y_LIMIT;
    return r ^ (settings.limit_invert & 3);
}

uint8_t inputs_read(void)
{
    uint8_t r = inputs_limits();
    uint8_t c = (uint8_t)(~PINC);
    if (c & (1 << ESTOP_BIT))
        r |= PIN_ESTOP;
    if (c & (1 << PAUSE_BIT))
        r |= PIN_PAUSE;
    if (c & (1 << RESUME_BIT))
        r |= PIN_RESUME;
    return r;
}

void inputs_homing(uint8_t on) { homing = on; }

void inputs_led(uint8_t on)
{
    if (on)
        PORTC |= 1 << LED_BIT;
    else
        PORTC &= ~(1 << LED_BIT);
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
