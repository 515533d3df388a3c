/* Timer2 counts at 250 kHz (4 us resolution); one overflow is 1.024 ms and a
 * frame is 20 overflows (20.48 ms, 48.8 Hz, which hobby servos accept).
 * Both pulse edges are made by the compare-output hardware ("set OC2A on
 * match", then "clear OC2A on match"), so the width does not depend on when
 * an interrupt runs: the interrupts only arm the next edge, and each edge is
 * placed at least 32 ticks (128 us) away from the overflow that arms it, far
 * more than the longest step interrupt. simavr 1.6 drives the pin from the
 * compare unit too (checked with a libsimavr harness watching PB3). */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <util/atomic.h>
#include "config.h"
#include "servo.h"

#define TICK_US 4
#define FRAME_OVERFLOWS 20
#define START_EARLY 64  /* tick of the rising edge, chosen so the falling */
#define START_LATE 160  /* edge lands away from an overflow too */

static volatile uint16_t pulse_ticks;
static uint16_t width_us;
static uint8_t frame_ovf;           /* overflows since the frame began */
static uint8_t fall_ovf, fall_tick; /* where this frame's falling edge is */

static void arm_rise(void)
{
    uint16_t w = pulse_ticks;
    uint8_t start = START_EARLY;
    uint8_t end = (uint8_t)((START_EARLY + w) & 0xFF);
    if (end < 32 || end > 224)
        start = START_LATE;
    uint16_t fall = (uint16_t)(start + w);
    fall_ovf = (uint8_t)(fall >> 8);
    fall_tick = (uint8_t)(fall & 0xFF);
    OCR2A = start;
    TCCR2A = (1 << COM2A1) | (1 << COM2A0); /* set on match */
}

static void arm_fall(void)
{
    OCR2A = fall_tick;
    TCCR2A = 1 << COM2A1; /* clear on match */
}

static volatile uint32_t ms;
static uint16_t ms_frac; /* thousandths of a ms: an overflow is 1.024 ms */

uint32_t timebase_ms(void)
{
    uint32_t v;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { v = ms; }
    return v;
}

ISR(TIMER2_OVF_vect)
{
    ms++;
    ms_frac += 24;
    if (ms_frac >= 1000) {
        ms_frac -= 1000;
        ms++;
    }
    if (++frame_ovf >= FRAME_OVERFLOWS)
        frame_ovf = 0;
    if (frame_ovf == 0)
        arm_rise();
    else if (frame_ovf == fall_ovf)
        arm_fall();
}

/* the rising edge has passed; a falling edge in the same overflow is armed now */
ISR(TIMER2_COMPA_vect)
{
    if (frame_ovf == 0 && fall_ovf == 0 && (TCCR2A & (1 << COM2A0)))
        arm_fall();
}

void servo_init(void)
{
    DDRB |= 1 << SERVO_BIT;
    servo_set_us(1000);
    TCCR2A = 1 << COM2A1; /* idle low */
    OCR2A = START_EARLY;
    TIMSK2 = (1 << TOIE2) | (1 << OCIE2A);
    TCCR2B = 1 << CS22;  /* clk/64 */
}

void servo_set_us(uint16_t us)
{
    if (us < 500)
        us = 500;
    if (us > 2500)
        us = 2500;
    width_us = us;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) { pulse_ticks = (uint16_t)((us + TICK_US / 2) / TICK_US); }
}

uint16_t servo_get_us(void) { return width_us; }
