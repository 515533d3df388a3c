/* Realtime requests raised from interrupts (serial bytes, buttons, limit
 * switches) and collected by the main loop. */
#ifndef REALTIME_H
#define REALTIME_H
#include <stdint.h>

#define RT_STATUS 0x01
#define RT_HOLD 0x02
#define RT_RESUME 0x04
#define RT_RESET 0x08
#define RT_ALARM 0x10   /* rt_alarm holds the code */
#define RT_JOG_CANCEL 0x20
#define RT_OVERRIDE 0x40 /* rt_ov changed: the planner takes the new feed/rapid percentages */

/* GRBL's override percentages: feed 10..200, rapid 25/50/100, spindle
 * 10..200 (the spindle is the pen: accepted and reported only) */
enum { OV_FEED, OV_RAPID, OV_SPINDLE };
extern volatile uint8_t rt_ov[3];
extern volatile uint8_t rt_flags;
extern volatile uint8_t rt_alarm;

uint8_t realtime_byte(uint8_t c);   /* receive interrupt, interrupts on: 1 if c was a realtime byte */
void realtime_raise(uint8_t flags); /* ISR or main */
void realtime_alarm_isr(uint8_t code); /* stop the steppers now and raise an alarm */
uint8_t realtime_take(void);        /* main: fetch and clear all flags */
#endif
