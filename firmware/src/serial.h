/* UART0 at 115200 8N1 with interrupt-driven rings; realtime bytes are taken
 * out of the stream in the receive interrupt. */
#ifndef SERIAL_H
#define SERIAL_H
#include <stdint.h>
#include "linebuf.h"

void serial_init(void);
/* Feed received bytes to lb up to the end of a line or of the bytes in:
 * linebuf_feed_ring's result for the last byte (LB_NONE: no line end yet). */
uint8_t serial_read_line(linebuf_t *lb);
void serial_write(uint8_t c);       /* blocks (servicing the watchdog) while the ring is full */
uint8_t serial_rx_free(void);
/* Set by the receive interrupt when a line end or half a ring of bytes
 * comes in; the main loop clears it before it reads. */
extern volatile uint8_t serial_rx_wake;
void serial_rx_flush(void);
uint8_t serial_tx_idle(void);
#endif
