/* The step tick (Timer1 compare A) in assembly, for the boards step_tick.h
 * names: the same work as the C tick in stepper.c, which the other boards
 * keep (read its comment for the timing design). Pins come from the board
 * header (through config.h); nothing here names one.
 *
 * Per tick: the pulse still up (if any) falls, the step computed last tick
 * rises, Timer0 restarts from 0 so its compare A ends the pulse $0 us
 * later; then one event of the segment under way: Bresenham per axis, the
 * step bit set in PENDING for the next tick. No step is counted: a block's
 * signed steps go into the position when it starts (the position is where
 * the block ends) and stepper.c's readers take off what its Bresenham
 * state says is still to come. A tick that finds its segment done takes
 * the slow path below (the next segment; a new block's Bresenham terms,
 * directions and steps; or the stop), in assembly too: as a C call it
 * cost the worst tick 11 register saves and restores on top. A tick that
 * outlasts the pulse ends it on its way out.
 *
 * Registers: SREG is kept in r0 (pushed); r24-r26 are the only others the
 * common path touches (a 16-bit subtract from memory needs a pair and one
 * byte: lds leaves the carry alone); the slow path saves the 4 more it
 * uses. r1 is not assumed zero (the interrupt may land mid-multiply).
 *
 * Cycle budget, measured by bench/firmware_bench.py at 50 kHz on both axes
 * (a period of 320 cycles), entry and exit included: on the 328P 103
 * cycles on average (74 body + 29 entry/exit: the response, the vector's
 * jump, 4 pushes and pops, reti), 275 at worst on the tick that loads a
 * block's first segment; on the 2560 105 and 277 (3-byte return
 * addresses). The C tick took 179/269 and 187/277. Per 0.5 mm line of the
 * bench's CPU-bound run (about 36 ticks) ~3,540 cycles on the 328P (the C
 * tick: 5,431); shorter than the 10 us step pulse, it leaves nearly every
 * pulse to Timer0's interrupt (21 cycles, ~545 a line), which is on for
 * the whole run: the tick no longer switches it on (2 cycles a tick). */
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

#if PENDING >= 0x20
#error "PENDING's bits are set with sbi: it must be in the low I/O space"
#endif

/* One axis's Bresenham event: counter -= steps; below 0, counter +=
 * events and the step bit goes into PENDING. No step is counted: the
 * position follows from this state (stepper.c's motor_at). 16 cycles
 * without a step, 23 with one. */
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
    sbi PENDING, \bit
1:  sts tick_counter + 2 * \axis, r24
    sts tick_counter + 2 * \axis + 1, r25
.endm

/* A block's first segment: one axis's |steps| (Z: its step_block_t) into
 * tick_steps, and signed (r23: the block's DIR_NEGATIVE) into the 32-bit
 * position, which then holds where the block ends. */
.macro BLOCK_AXIS axis
    ldd r24, Z + BLK_STEPS_AT + 2 * \axis
    ldd r25, Z + BLK_STEPS_AT + 2 * \axis + 1
    sts tick_steps + 2 * \axis, r24
    sts tick_steps + 2 * \axis + 1, r25
    ldi r27, 0              /* the high bytes' addend: the sign */
    sbrs r23, \axis
    rjmp 1f
    com r25                 /* negative: -steps */
    neg r24
    sbci r25, 0xFF
    ldi r27, 0xFF
1:  lds r26, tick_position + 4 * \axis
    add r26, r24
    sts tick_position + 4 * \axis, r26
    lds r26, tick_position + 4 * \axis + 1
    adc r26, r25
    sts tick_position + 4 * \axis + 1, r26
    lds r26, tick_position + 4 * \axis + 2
    adc r26, r27
    sts tick_position + 4 * \axis + 2, r26
    lds r26, tick_position + 4 * \axis + 3
    adc r26, r27
    sts tick_position + 4 * \axis + 3, r26
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
    out IO(TCNT0), r24      /* compare A (OCR0A = $0) ends the pulse */
    /* Timer0's interrupt is on for the whole run (stepper.c): only a
     * compare that came (at its 128 us wrap) before the count's reset is
     * dropped, or it would end the pulse just raised */
    ldi r24, 1 << OCF0A
    out IO(TIFR0), r24
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
    ldi r24, 1 << OCF0A     /* (its interrupt has nothing left to end) */
    out IO(TIFR0), r24
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

/* The slow path, once a segment: the next segment from the ring (its
 * period, its events; a block's first also its Bresenham terms, directions
 * and steps), or the stop when the ring is empty (the pulse just raised is
 * still ended by Timer0's interrupt). stepper.c's C tick does the same in
 * tick_load. r24:r25 come in as 0xFFFF (left 0, less 1). */
load:
    push r23
    push r27
    push r30
    push r31
    lds r24, seg_head
    lds r30, seg_tail
    cp r24, r30
    brne 1f
    ldi r24, 1 << WGM12     /* Timer1's clock off; its interrupt off: stopped */
    sts TCCR1B, r24
    ldi r24, 0
    sts TIMSK1, r24
    pop r31
    pop r30
    pop r27
    pop r23
    rjmp done
1:  andi r30, SEG_SIZE - 1  /* Z = &seg_ring[slot]: slot * 7 */
    mov r24, r30
    lsl r30
    lsl r30
    lsl r30
    sub r30, r24
    ldi r31, 0
    subi r30, lo8(-(seg_ring))
    sbci r31, hi8(-(seg_ring))
    ldd r24, Z + SEG_PERIOD_AT
    ldd r25, Z + SEG_PERIOD_AT + 1
    sts OCR1AH, r25         /* the high byte first: the timer latches it */
    sts OCR1AL, r24
    ldd r26, Z + SEG_FLAGS_AT
    ldd r24, Z + SEG_EVENTS_AT
    ldd r25, Z + SEG_EVENTS_AT + 1
    sbrc r26, SEG_FIRST_BIT
    rjmp 2f
    /* the block goes on: its events so far */
    lds r26, tick_k
    add r26, r24
    sts tick_k, r26
    lds r26, tick_k + 1
    adc r26, r25
    sts tick_k + 1, r26
    rjmp 3f
2:  /* a block's first segment */
    sts tick_k, r24
    sts tick_k + 1, r25
    ldd r26, Z + SEG_BLOCK_AT
    ldd r31, Z + SEG_BLOCK_AT + 1
    mov r30, r26            /* Z = its step_block_t */
    ldd r23, Z + BLK_DIR_AT
    out DIR_NEGATIVE, r23
    /* directions, a whole period before the block's first edge (as
     * drive_set_dir: HIGH = negative at $3=0) */
    lds r26, tick_dir_invert
    eor r26, r23
    sbrc r26, 0
    sbi IO(IO_PORT(X_DIR)), IO_BIT(X_DIR)
    sbrs r26, 0
    cbi IO(IO_PORT(X_DIR)), IO_BIT(X_DIR)
    sbrc r26, 1
    sbi IO(IO_PORT(Y_DIR)), IO_BIT(Y_DIR)
    sbrs r26, 1
    cbi IO(IO_PORT(Y_DIR)), IO_BIT(Y_DIR)
    ldd r24, Z + BLK_EVENTS_AT
    ldd r25, Z + BLK_EVENTS_AT + 1
    sts tick_events, r24
    sts tick_events + 1, r25
    asr r25                 /* both counters start at events / 2 */
    ror r24
    sts tick_counter, r24
    sts tick_counter + 1, r25
    sts tick_counter + 2, r24
    sts tick_counter + 3, r25
    BLOCK_AXIS 0
    BLOCK_AXIS 1
    lds r24, tick_k         /* the segment's events */
    lds r25, tick_k + 1
3:  pop r31
    pop r30
    pop r27
    pop r23
    sbiw r24, 1             /* (a segment has at least 1 event) */
    rjmp counted
    .size TIMER1_COMPA_vect, . - TIMER1_COMPA_vect

#endif
