#include "pty_link.h"

#include <errno.h>
#include <fcntl.h>
#include <pty.h>
#include <stdio.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

#include "avr_uart.h"

/* ATmega328P USART0 registers (data-space addresses) */
#define REG_UCSR0A 0xC0
#define REG_UBRR0L 0xC4
#define REG_UBRR0H 0xC5
#define BIT_U2X0 1
#define BITS_PER_FRAME 10 /* 8N1: start, 8 data, stop */

static avr_cycle_count_t cycles_per_byte(avr_t *avr)
{
	unsigned ubrr = avr->data[REG_UBRR0L] | ((avr->data[REG_UBRR0H] & 0x0F) << 8);
	unsigned div = (avr->data[REG_UCSR0A] & (1 << BIT_U2X0)) ? 8 : 16;
	return (avr_cycle_count_t)(ubrr + 1) * div * BITS_PER_FRAME;
}

/* Delivers the next host byte to the UART, one per frame time. */
static avr_cycle_count_t rx_pump(avr_t *avr, avr_cycle_count_t when, void *param)
{
	struct pty_link *p = param;
	if (p->rx_len == 0) {
		p->pumping = 0;
		return 0;
	}
	if (!p->xoff) {
		uint8_t b = p->rx[p->rx_head];
		p->rx_head = (p->rx_head + 1) % PTY_RX_SIZE;
		p->rx_len--;
		avr_raise_irq(p->uart_in, b);
	}
	return when + cycles_per_byte(avr);
}

static void uart_out(struct avr_irq_t *irq, uint32_t value, void *param)
{
	(void)irq;
	struct pty_link *p = param;
	if (p->tx_len == PTY_TX_SIZE) {
		p->dropped++;
		return;
	}
	p->tx[(p->tx_head + p->tx_len) % PTY_TX_SIZE] = (uint8_t)value;
	p->tx_len++;
}

static void uart_xoff(struct avr_irq_t *irq, uint32_t value, void *param)
{
	(void)irq;
	struct pty_link *p = param;
	p->xoff = value != 0;
}

static void uart_xon(struct avr_irq_t *irq, uint32_t value, void *param)
{
	(void)irq;
	struct pty_link *p = param;
	if (value)
		p->xoff = 0;
}

int pty_link_open(struct pty_link *p, avr_t *avr, const char *link_path, char *err, size_t errlen)
{
	memset(p, 0, sizeof *p);
	p->master = p->slave = -1;
	p->avr = avr;
	if (openpty(&p->master, &p->slave, p->name, NULL, NULL) < 0) {
		snprintf(err, errlen, "openpty: %s", strerror(errno));
		return -1;
	}
	/* We keep the slave open so its raw settings persist between clients and
	 * the master never sees a hang-up. */
	struct termios tio;
	tcgetattr(p->slave, &tio);
	cfmakeraw(&tio);
	tcsetattr(p->slave, TCSANOW, &tio);
	fcntl(p->master, F_SETFL, fcntl(p->master, F_GETFL) | O_NONBLOCK);
	fcntl(p->master, F_SETFD, FD_CLOEXEC);
	fcntl(p->slave, F_SETFD, FD_CLOEXEC);

	if (link_path && *link_path) {
		char tmp[600];
		if (strlen(link_path) >= sizeof p->link_path) {
			snprintf(err, errlen, "--pty-link path too long");
			return -1;
		}
		snprintf(tmp, sizeof tmp, "%s.%d.tmp", link_path, (int)getpid());
		unlink(tmp);
		if (symlink(p->name, tmp) < 0 || rename(tmp, link_path) < 0) {
			snprintf(err, errlen, "--pty-link %s: %s", link_path, strerror(errno));
			unlink(tmp);
			return -1;
		}
		snprintf(p->link_path, sizeof p->link_path, "%s", link_path);
	}

	uint32_t flags = 0;
	avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
	/* no console echo of UART lines, no usleep when the firmware polls UCSR0A */
	flags &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
	avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
	p->uart_in = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
	avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
				uart_out, p);
	avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF),
				uart_xoff, p);
	avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON),
				uart_xon, p);
	return 0;
}

void pty_link_service(struct pty_link *p)
{
	/* read only what fits: the rest waits in the kernel, which throttles the host */
	while (p->rx_len < PTY_RX_SIZE) {
		size_t tail = (p->rx_head + p->rx_len) % PTY_RX_SIZE;
		size_t room = PTY_RX_SIZE - p->rx_len;
		if (tail + room > PTY_RX_SIZE)
			room = PTY_RX_SIZE - tail;
		ssize_t n = read(p->master, p->rx + tail, room);
		if (n <= 0)
			break;
		p->rx_len += (size_t)n;
	}
	/* a chip reset cancels all cycle timers, the pump's too */
	if (p->pumping && avr_cycle_timer_status(p->avr, rx_pump, p) == 0)
		p->pumping = 0;
	if (p->rx_len && !p->pumping) {
		p->pumping = 1;
		avr_cycle_timer_register(p->avr, cycles_per_byte(p->avr), rx_pump, p);
	}
	while (p->tx_len) {
		size_t chunk = p->tx_len;
		if (p->tx_head + chunk > PTY_TX_SIZE)
			chunk = PTY_TX_SIZE - p->tx_head;
		ssize_t n = write(p->master, p->tx + p->tx_head, chunk);
		if (n < 0 && errno == EAGAIN) {
			/* nobody is reading the pty: a UART with no listener loses bytes */
			p->dropped += p->tx_len;
			p->tx_len = 0;
			break;
		}
		if (n <= 0)
			break;
		p->tx_head = (p->tx_head + (size_t)n) % PTY_TX_SIZE;
		p->tx_len -= (size_t)n;
	}
	if (p->tx_len == 0)
		p->tx_head = 0;
}

int pty_link_pending_tx(const struct pty_link *p)
{
	return p->tx_len != 0;
}

void pty_link_close(struct pty_link *p)
{
	if (p->link_path[0]) {
		char target[64];
		ssize_t n = readlink(p->link_path, target, sizeof target - 1);
		if (n > 0) {
			target[n] = 0;
			if (strcmp(target, p->name) == 0)
				unlink(p->link_path);
		}
	}
	if (p->master >= 0)
		close(p->master);
	if (p->slave >= 0)
		close(p->slave);
	p->master = p->slave = -1;
}
