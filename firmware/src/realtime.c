#include <avr/interrupt.h>
#include <util/atomic.h>
#include "realtime.h"
#include "stepper.h"
#include "status.h"

volatile uint8_t rt_flags;
volatile uint8_t rt_alarm;

void realtime_raise(uint8_t flags)
{
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { rt_flags |= flags; }
}

void realtime_alarm_isr(uint8_t code)
{
    stepper_halt();
    /* the first alarm wins: ALARM:10 is not overwritten by a limit it caused */
    if (!rt_alarm)
        rt_alarm = code;
    rt_flags |= RT_ALARM;
}

uint8_t realtime_byte(uint8_t c)
{
    switch (c) {
    case '?': rt_flags |= RT_STATUS; return 1;
    case '!': rt_flags |= RT_HOLD; return 1;
    case '~': rt_flags |= RT_RESUME; return 1;
    case 0x85: rt_flags |= RT_JOG_CANCEL; return 1;
    case 0x18:
        /* stop at once; a reset that interrupts motion loses the position */
        if (stepper_halt())
            realtime_alarm_isr(ALARM_ABORT_CYCLE);
        rt_flags |= RT_RESET;
        return 1;
    default:
        /* GRBL's other extended realtime commands (overrides, 0x80-0xFF) are
         * not supported: swallowed here, so they never corrupt a line */
        return c >= 0x80;
    }
}

uint8_t realtime_take(void)
{
    uint8_t f;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        f = rt_flags;
        rt_flags = 0;
    }
    return f;
}
