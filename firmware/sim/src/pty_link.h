/* UART0 <-> a pseudo-terminal. No thread: the simulation loop polls the pty.
 * Bytes from the host enter the UART one per byte time at the baud rate the
 * firmware programmed; bytes the firmware sends leave as the UART emits them
 * (its own byte timing), so the serial timing is simulated time in every mode. */
#ifndef PTY_LINK_H
#define PTY_LINK_H

#include <stddef.h>
#include <stdint.h>

#include "sim_avr.h"

#define PTY_RX_SIZE 4096
#define PTY_TX_SIZE 8192

struct pty_link {
	int master, slave;
	char name[64];
	char link_path[512];     /* empty: no symlink */
	avr_t *avr;
	avr_irq_t *uart_in;
	uint8_t rx[PTY_RX_SIZE];  /* host -> firmware, waiting for the wire */
	size_t rx_head, rx_len;
	uint8_t tx[PTY_TX_SIZE];  /* firmware -> host, waiting for the pty */
	size_t tx_head, tx_len;
	int xoff, pumping;
	uint64_t dropped;         /* firmware output nobody read */
};

int pty_link_open(struct pty_link *p, avr_t *avr, const char *link_path, char *err, size_t errlen);
/* move bytes between the pty and the queues; call from the simulation loop */
void pty_link_service(struct pty_link *p);
/* does the loop need to wake up for writability? */
int pty_link_pending_tx(const struct pty_link *p);
void pty_link_close(struct pty_link *p);

#endif
