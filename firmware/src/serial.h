/* UART0 at 115200 8N1 with interrupt-driven rings; realtime bytes are taken
 * out of the stream in the receive interrupt. */
#ifndef SERIAL_H
#define SERIAL_H
#include <stdint.h>

#define SERIAL_NO_DATA 0xFFFF

void serial_init(void);
uint16_t serial_read(void);         /* next byte, or SERIAL_NO_DATA */
void serial_write(uint8_t c);       /* blocks (servicing the watchdog) while the ring is full */
uint8_t serial_rx_free(void);
void serial_rx_flush(void);
uint8_t serial_tx_idle(void);
#endif
