#include "reset_fix.h"

#include <string.h>

#include "avr_extint.h"
#include "avr_ioport.h"

#define MAX_WRAPPED 8

struct wrapped {
	avr_io_t *io;
	void (*orig)(avr_io_t *io);
};

static struct wrapped wrapped[MAX_WRAPPED];
static int nwrapped;

static struct wrapped *find(avr_io_t *io)
{
	for (int i = 0; i < nwrapped; i++)
		if (wrapped[i].io == io)
			return &wrapped[i];
	return NULL;
}

/* PINx shows the level each pin's IRQ last carried, as the pins still do */
static void port_reset(avr_io_t *io)
{
	find(io)->orig(io);
	avr_ioport_t *p = (avr_ioport_t *)io;
	uint8_t pin = 0;
	for (int i = 0; i < 8; i++)
		if (io->irq[i].value)
			pin |= (uint8_t)(1u << i);
	io->avr->data[p->r_pin] = pin;
}

static void extint_reset(avr_io_t *io)
{
	find(io)->orig(io);
	/* level polling of INT0/INT1 costs 60% of the run time: off, as at start */
	avr_extint_set_strict_lvl_trig(io->avr, 0, 0);
	avr_extint_set_strict_lvl_trig(io->avr, 1, 0);
}

void reset_fix_install(avr_t *avr)
{
	for (avr_io_t *io = avr->io_port; io && nwrapped < MAX_WRAPPED; io = io->next) {
		void (*fix)(avr_io_t *) = NULL;
		if (io->kind && strcmp(io->kind, "port") == 0)
			fix = port_reset;
		else if (io->kind && strcmp(io->kind, "extint") == 0)
			fix = extint_reset;
		if (!fix || !io->reset)
			continue;
		wrapped[nwrapped++] = (struct wrapped){ .io = io, .orig = io->reset };
		io->reset = fix;
	}
	avr_extint_set_strict_lvl_trig(avr, 0, 0);
	avr_extint_set_strict_lvl_trig(avr, 1, 0);
}
