/* Where simavr 1.6's timers differ from the ATmega328P, make them behave as
 * the chip does (DESIGN.md "simavr 1.6: facts that bite"):
 *  - an interrupt whose flag is already set fires as soon as it is enabled;
 *  - a counter written while the timer's clock is stopped keeps that count
 *    when the clock starts (simavr restarts from 0);
 *  - CTC with a compare value of 0 matches at once when the clock starts
 *    (simavr never schedules it): the compare interrupt is raised once.
 * The pin decoder still measures every pulse, so a miss would show anyway. */
#ifndef TIMER_FIX_H
#define TIMER_FIX_H

#include "sim_avr.h"

void timer_fix_install(avr_t *avr);

#endif
