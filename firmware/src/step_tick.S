/* The step tick (Timer1 compare A) in assembly, for the boards step_tick.h
 * names: the same work as the C tick in stepper.c, which the other boards
 * keep (read its comment for the timing design), at about two thirds of
 * its cycles. Pins come from the board header (through config.h); nothing
 * here names one.
 *
 * Per tick: the pulse still up (if any) falls, the step computed last tick
 * rises, Timer0 restarts from 0 so its compare A ends the pulse $0 us
 * later; then one event of the segment under way: Bresenham per axis, the
 * step bit set in PENDING for the next tick, the axis's count moved by one
 * toward its direction. A tick that finds its segment done calls the C slow
 * path (stepper_tick_load: the next segment, a new block's Bresenham terms
 * and directions, or the stop). A tick that outlasts the pulse ends it on
 * its way out.
 *
 * Registers: SREG is kept in r0 (pushed); r24-r26 are the only others the
 * common path touches (a 16-bit subtract from memory needs a pair and one
 * byte: lds leaves the carry alone). The slow path saves what a C call may
 * clobber itself, so the common path does not pay for it. r1 is not
 * assumed zero (the interrupt may land mid-multiply).
 *
 * Cycle budget, measured by bench/firmware_bench.py at 50 kHz on both axes
 * (a period of 320 cycles), entry and exit included: on the 328P 140 cycles
 * on average (111 body + 29 entry/exit: the response, the vector's jump,
 * 4 pushes and pops, reti), 303 at worst on the tick that loads a segment
 * (the slow path's 11 saves and the C call); on the 2560 142 and 307 (its
 * 3-byte return addresses). The C tick took 179/269 and 187/277. Per 0.5 mm
 * line of the bench's CPU-bound run (about 36 ticks) 4,317 cycles on the
 * 328P plus ~110 in stepper_tick_load (the C tick: 5,431); being shorter
 * than the step pulse, it now leaves most pulses to Timer0's interrupt
 * (~15 a line, 23 cycles each). */
#include <avr/io.h>
#include "step_tick.h"

#if STEP_TICK_ASM

#define IO(reg) _SFR_IO_ADDR(reg)
#define STEP_PIN IO(IO_PINREG(X_STEP))  /* a write toggles the bits set */
#define X_BIT IO_BIT(X_STEP)            /* DRIVE_X: the pin's own bit */
#define Y_BIT IO_BIT(Y_STEP)            /* DRIVE_Y */
#define PENDING IO(GPIOR0)              /* stepper.c's PENDING_STEPS */
#define DIR_NEGATIVE IO(GPIOR1)         /* stepper.c's DIR_NEGATIVE */
#define PULSING IO(GPIOR2)              /* drive_stepdir.h's drive_pulsing */

#if OCF0A != OCIE0A
#error "one value is written to TIFR0 and TIMSK0: their compare A bits must match"
#endif
#if PENDING >= 0x20
#error "PENDING's bits are set with sbi: it must be in the low I/O space"
#endif

/* One axis's Bresenham event. counter -= steps; below 0: counter += events,
 * the step bit goes into PENDING, the count moves by one (down when the
 * axis's DIR_NEGATIVE bit is set: sbiw 2 then adiw 1). 16 cycles without a
 * step, 36 or 37 with one. */
.macro BRESENHAM axis, bit
    lds r24, tick_counter + 2 * \axis
    lds r25, tick_counter + 2 * \axis + 1
    lds r26, tick_steps + 2 * \axis
    sub r24, r26
    lds r26, tick_steps + 2 * \axis + 1
    sbc r25, r26
    brpl 1f
    lds r26, tick_events
    add r24, r26
    lds r26, tick_events + 1
    adc r25, r26
    sts tick_counter + 2 * \axis, r24
    sts tick_counter + 2 * \axis + 1, r25
    sbi PENDING, \bit
    lds r24, tick_done + 2 * \axis
    lds r25, tick_done + 2 * \axis + 1
    in r26, DIR_NEGATIVE
    sbrc r26, \axis
    sbiw r24, 2
    adiw r24, 1
    sts tick_done + 2 * \axis, r24
    sts tick_done + 2 * \axis + 1, r25
    rjmp 2f
1:  sts tick_counter + 2 * \axis, r24
    sts tick_counter + 2 * \axis + 1, r25
2:
.endm

    .section .text.step_tick,"ax",@progbits
    .global TIMER1_COMPA_vect
    .type TIMER1_COMPA_vect, @function
TIMER1_COMPA_vect:
    push r0
    in r0, IO(SREG)
    push r24
    push r25
    push r26
#ifdef BENCH_ISR_PIN
    sbi IO(IO_PORT(BENCH_ISR)), IO_BIT(BENCH_ISR)
#endif
    /* a pulse still up (its end came late: never at the planned rates)
     * falls first, keeping edges paired (with none up this writes 0: no
     * toggle) */
    in r24, PULSING
    out STEP_PIN, r24
    /* the step computed last tick: its edge at a fixed time after entry */
    in r24, PENDING
    out STEP_PIN, r24
    out PULSING, r24
    ldi r24, 0
    out PENDING, r24        /* the event below sets its bits afresh */
    out IO(TCNT0), r24      /* compare A (OCR0A = $0) ends the pulse; no wrap */
    ldi r24, 1 << OCF0A
    out IO(TIFR0), r24
    sts TIMSK0, r24
    /* the segment: none left -> the slow path loads the next one */
    lds r24, tick_left
    lds r25, tick_left + 1
    sbiw r24, 1
    brcs load_near
counted:
    brne 3f
    /* the segment's last event: its slot may be refilled (the slow path
     * copied all of it) */
    lds r26, seg_tail
    inc r26
    sts seg_tail, r26
    rjmp 3f
load_near:
    rjmp load               /* (a branch reaches 64 words) */
3:  sts tick_left, r24
    sts tick_left + 1, r25
    BRESENHAM 0, X_BIT
    BRESENHAM 1, Y_BIT
    /* a long tick (a segment load) outlasted the pulse: end it now rather
     * than after the next tick, which outranks Timer0's interrupt */
    sbis IO(TIFR0), OCF0A
    rjmp done
    in r24, PULSING
    out STEP_PIN, r24
    ldi r24, 0
    out PULSING, r24
    sts TIMSK0, r24
done:
#ifdef BENCH_ISR_PIN
    cbi IO(IO_PORT(BENCH_ISR)), IO_BIT(BENCH_ISR)
#endif
    pop r26
    pop r25
    pop r24
    out IO(SREG), r0
    pop r0
    reti

/* The slow path: a C call, so the registers it may clobber are saved here
 * (r0 holds SREG; r1 must be zero in C). Stopped (0 events): the pulse
 * just raised is still ended by Timer0's interrupt. */
load:
    push r0
    push r1
    push r18
    push r19
    push r20
    push r21
    push r22
    push r23
    push r27
    push r30
    push r31
    clr r1
    call stepper_tick_load
    pop r31
    pop r30
    pop r27
    pop r23
    pop r22
    pop r21
    pop r20
    pop r19
    pop r18
    pop r1
    pop r0
    sbiw r24, 1
    brcs 1f
    rjmp counted
1:  rjmp done
    .size TIMER1_COMPA_vect, . - TIMER1_COMPA_vect

#endif
