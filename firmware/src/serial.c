#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/wdt.h>
#include "config.h"
#include "linebuf.h"
#include "realtime.h"
#include "ring.h"
#include "serial.h"

/* the 2560 numbers its four UARTs: ours is UART0 (pins 0/1, the USB bridge) */
#ifdef USART0_RX_vect
#define UART_RX_VECT USART0_RX_vect
#define UART_UDRE_VECT USART0_UDRE_vect
#else
#define UART_RX_VECT USART_RX_vect
#define UART_UDRE_VECT USART_UDRE_vect
#endif

static uint8_t rx_buf[RX_SIZE];
static volatile uint8_t rx_head, rx_tail;
volatile uint8_t serial_rx_wake;
static uint8_t tx_buf[TX_SIZE];
static volatile uint8_t tx_head, tx_tail;

void serial_init(void)
{
    /* U2X: 115200 from 16 MHz is 2.1% off without it, -0.8% with it;
     * 9600 (HC-06) is 0.2% off. */
    UCSR0A = (1 << U2X0);
    UBRR0 = (uint16_t)((F_CPU + 4UL * DEFAULT_BAUD) / (8UL * DEFAULT_BAUD) - 1);
    UCSR0B = (1 << RXEN0) | (1 << TXEN0) | (1 << RXCIE0);
    UCSR0C = (1 << UCSZ01) | (1 << UCSZ00);
}

/* realtime_byte called from the receive interrupt through a trampoline that
 * saves the call-clobbered registers itself: the compiler sees no call in
 * the interrupt, so a line's ordinary bytes (all but the realtime ones) no
 * longer pay for pushing and popping the 11 registers a call may clobber
 * (44 cycles a byte). The trampoline keeps the ABI: r1 is 0 in an interrupt
 * body, r0 is scratch, r24 carries the byte in and the answer out. */
__asm__(".pushsection .text.realtime_byte_saving,\"ax\",@progbits\n"
        "realtime_byte_saving:\n"
        "  push r18\n  push r19\n  push r20\n  push r21\n  push r22\n  push r23\n"
        "  push r25\n  push r26\n  push r27\n  push r30\n  push r31\n"
        "  call realtime_byte\n"
        "  pop r31\n  pop r30\n  pop r27\n  pop r26\n  pop r25\n"
        "  pop r23\n  pop r22\n  pop r21\n  pop r20\n  pop r19\n  pop r18\n"
        "  ret\n"
        ".popsection\n");

/* With interrupts on: a step tick due meanwhile goes first (held up by the
 * ~150 cycles of this path it would come late enough to read as a faster
 * step rate), with this interrupt's own source off so that a byte already
 * waiting in the UART cannot nest in ahead of this one. realtime.c's
 * updates of the flags other interrupts also raise are atomic. */
static inline __attribute__((always_inline)) uint8_t realtime_byte_in_isr(uint8_t c)
{
    register uint8_t b __asm__("r24") = c;
    UCSR0B &= (uint8_t)~(1 << RXCIE0);
    sei();
    __asm__ volatile("call realtime_byte_saving" : "+r"(b) : : "memory");
    cli();
    UCSR0B |= 1 << RXCIE0;
    return b;
}

/* Cycle budget, measured in the bench's CPU-bound run (bench/firmware_bench.py
 * --profile, __vector_18 over the bytes of a line): about 82 cycles a byte
 * of a line, entry and exit included; a realtime byte adds the trampoline
 * and realtime_byte (a reset: the steppers' halt). */
ISR(UART_RX_VECT)
{
    uint8_t c = UDR0;
    /* realtime_byte only for the bytes it may take ('?', '!', '~', 0x18 and
     * 0x7E..0xFF) */
    if ((c >= '~' || c == '?' || c == '!' || c == 0x18) && realtime_byte_in_isr(c))
        return;
    uint8_t head = rx_head;
    uint8_t n = ring_count(head, rx_tail);
    if (n < RX_SIZE) {
        rx_buf[ring_slot(head, RX_SIZE)] = c;
        rx_head = (uint8_t)(head + 1);
    } /* a full ring drops the byte: a sender that counts never gets here */
    /* the main loop sleeps through a line's bytes: wake it for a whole line,
     * or for half a ring (a line longer than the ring is read in pieces) */
    if (c == '\n' || c == '\r' || n >= RX_SIZE / 2)
        serial_rx_wake = 1;
}

uint8_t serial_read_line(linebuf_t *lb)
{
    uint8_t tail = rx_tail;
    uint8_t r = linebuf_feed_ring(lb, rx_buf, RX_SIZE - 1, &tail, rx_head);
    rx_tail = tail; /* once: the bytes taken are free for the interrupt now */
    return r;
}

uint8_t serial_rx_free(void) { return ring_free(rx_head, rx_tail, RX_SIZE); }

void serial_rx_flush(void)
{
    cli();
    rx_tail = rx_head;
    sei();
}

/* Cycle budget: about 64 cycles a byte, entry and exit included (the
 * bench's profile: ~255 a line for the 4 bytes of "ok\r\n"; head and tail
 * are read once). */
ISR(UART_UDRE_VECT)
{
    uint8_t tail = tx_tail, head = tx_head;
    if (tail != head) {
        UDR0 = tx_buf[ring_slot(tail, TX_SIZE)];
        tx_tail = ++tail;
    }
    if (tail == head) /* drained: serial_write turns it on again with its next byte */
        UCSR0B &= (uint8_t)~(1 << UDRIE0);
}

void serial_write(uint8_t c)
{
    while (ring_count(tx_head, tx_tail) >= TX_SIZE)
        wdt_reset();
    tx_buf[ring_slot(tx_head, TX_SIZE)] = c;
    tx_head++;
    UCSR0B |= (1 << UDRIE0);
}

uint8_t serial_tx_idle(void) { return tx_head == tx_tail; }
