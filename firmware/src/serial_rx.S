/* The UART receive interrupt in assembly (every board): serial.c's ring,
 * filled here, read by serial_read_line.
 *
 * An ordinary byte goes into the ring (a full ring drops it: a sender that
 * counts characters never gets there) and wakes the main loop on a line end
 * or once the ring is half full (a line longer than the ring is read in
 * pieces). A byte realtime_byte may take ('?', '!', '~', 0x18 and
 * 0x7E..0xFF) is handed to it with interrupts on (a step tick due meanwhile
 * goes first: held up by this path it would come late enough to read as a
 * faster step rate) and this interrupt's own source off (a byte already
 * waiting in the UART cannot nest in ahead of this one); a byte it does not
 * take (0x7E..0xFF but unknown, 0x7F) goes on into the ring.
 *
 * Registers: SREG kept in r0; the byte, the head and Z for the store; the
 * realtime path saves the rest a C call may clobber itself (r0 too: SREG's
 * copy), so an ordinary byte does not pay for it.
 *
 * Cycle budget, measured in the bench's CPU-bound run (bench/firmware_bench.py
 * --profile, the vector over the 13.7 bytes of a compact line): about 60
 * cycles an ordinary byte on the 328P (823 a line), 61 on the 2560 (842),
 * entry and exit included (the C version: ~82, 1,125 a line); a realtime
 * byte adds 22 saves and restores and realtime_byte (a reset: the steppers'
 * halt). An ordinary byte runs with interrupts shut throughout: a due step
 * tick waits at most its ~60 cycles (the realtime path opens them before
 * its call). */
#include <avr/io.h>
#include "config.h"

/* the 2560 numbers its four UARTs: ours is UART0 (pins 0/1, the USB bridge) */
#ifdef USART0_RX_vect
#define UART_RX_VECT USART0_RX_vect
#else
#define UART_RX_VECT USART_RX_vect
#endif

#if RX_SIZE > 128 || (RX_SIZE & (RX_SIZE - 1))
#error "the receive ring's free-running 8-bit indices need a power of two up to 128"
#endif

    .section .text.serial_rx,"ax",@progbits
    .global UART_RX_VECT
    .type UART_RX_VECT, @function
UART_RX_VECT:
    push r0
    in r0, _SFR_IO_ADDR(SREG)
    push r24
    push r25
    push r30
    push r31
    lds r24, UDR0
    cpi r24, 0x7E            /* '~' and up */
    brsh realtime
    cpi r24, 0x3F            /* '?' */
    breq realtime
    cpi r24, 0x21            /* '!' */
    breq realtime
    cpi r24, 0x18            /* soft reset */
    breq realtime
ordinary:
    lds r25, serial_rx_head
    lds r30, serial_rx_tail
    neg r30
    add r30, r25            /* bytes in the ring */
    cpi r30, RX_SIZE / 2
    brsh half
    cpi r24, 0x0A            /* '\n' */
    breq 1f
    cpi r24, 0x0D            /* '\r' */
    brne store
1:  ldi r30, 1
    sts serial_rx_wake, r30
store:
    mov r30, r25
    andi r30, RX_SIZE - 1
    ldi r31, 0
    subi r30, lo8(-(serial_rx_buf))
    sbci r31, hi8(-(serial_rx_buf))
    st Z, r24
    subi r25, -1
    sts serial_rx_head, r25
done:
    pop r31
    pop r30
    pop r25
    pop r24
    out _SFR_IO_ADDR(SREG), r0
    pop r0
    reti

/* half a ring or more: wake the main loop; store unless full */
half:
    ldi r31, 1
    sts serial_rx_wake, r31
    cpi r30, RX_SIZE
    brlo store
    rjmp done

/* realtime_byte(c) (r24 in, r24 out: 1 if it took the byte), with
 * interrupts on from before the saves to after the restores (nested
 * interrupts keep their own registers) and this interrupt's source off */
realtime:
    lds r25, UCSR0B
    andi r25, ~(1 << RXCIE0)
    sts UCSR0B, r25
    sei
    push r0                 /* SREG's copy: r0 is scratch to C */
    push r1
    push r18
    push r19
    push r20
    push r21
    push r22
    push r23
    push r26
    push r27
    push r24                /* the byte, for the ring if it is not taken */
    clr r1
    call realtime_byte
    mov r25, r24
    pop r24
    pop r27
    pop r26
    pop r23
    pop r22
    pop r21
    pop r20
    pop r19
    pop r18
    pop r1
    pop r0
    cli
    lds r30, UCSR0B
    ori r30, 1 << RXCIE0
    sts UCSR0B, r30
    tst r25
    brne done
    rjmp ordinary
    .size UART_RX_VECT, . - UART_RX_VECT
