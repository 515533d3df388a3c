#include <avr/interrupt.h>
#include <util/atomic.h>
#include "realtime.h"
#include "stepper.h"
#include "status.h"

volatile uint8_t rt_flags;
volatile uint8_t rt_alarm;
volatile uint8_t rt_ov[3] = {100, 100, 100};

/* 0x90-0x94 feed and 0x99-0x9D spindle: reset to 100, +10, -10, +1, -1,
 * kept within 10..200 */
static void step_override(uint8_t which, uint8_t op)
{
    int8_t d = op <= 2 ? 10 : 1; /* no table: it would sit in RAM */
    if (!(op & 1))
        d = (int8_t)-d;
    int16_t v = op ? rt_ov[which] + d : 100;
    rt_ov[which] = (uint8_t)(v < 10 ? 10 : v > 200 ? 200 : v);
}

void realtime_raise(uint8_t flags)
{
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { rt_flags |= flags; }
}

void realtime_alarm_isr(uint8_t code)
{
    stepper_halt();
    /* atomic: the receive interrupt calls this with interrupts on, and a
     * limit or button interrupt may come in between */
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        /* the first alarm wins: ALARM:10 is not overwritten by a limit it caused */
        if (!rt_alarm)
            rt_alarm = code;
        rt_flags |= RT_ALARM;
    }
}

/* The receive interrupt calls this with interrupts on (serial.c): the flags
 * go up through realtime_raise, atomic against the limit and button
 * interrupts that raise them too. */
uint8_t realtime_byte(uint8_t c)
{
    uint8_t flag;
    switch (c) {
    case '?': flag = RT_STATUS; break;
    case '!': flag = RT_HOLD; break;
    case '~': flag = RT_RESUME; break;
    case 0x85: flag = RT_JOG_CANCEL; break;
    case 0x18:
        /* stop at once; a reset that interrupts motion loses the position */
        if (stepper_halt())
            realtime_alarm_isr(ALARM_ABORT_CYCLE);
        flag = RT_RESET;
        break;
    default:
        if (c >= 0x90 && c <= 0x94)
            step_override(OV_FEED, (uint8_t)(c - 0x90));
        else if (c >= 0x95 && c <= 0x97)
            rt_ov[OV_RAPID] = (uint8_t)(100 >> (c - 0x95)); /* 100, 50, 25 */
        else if (c >= 0x99 && c <= 0x9D)
            step_override(OV_SPINDLE, (uint8_t)(c - 0x99));
        else /* GRBL's other extended bytes (0x80-0xFF): swallowed, never part of a line */
            return c >= 0x80;
        flag = RT_OVERRIDE;
    }
    realtime_raise(flag);
    return 1;
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
