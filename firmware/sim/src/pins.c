#include "pins.h"

#include "avr_ioport.h"

enum { H_STEP, H_DIR, H_ENABLE, H_SERVO, H_LED, H_COILS };

static uint64_t now(struct pins *p)
{
	return p->avr->cycle;
}

static avr_irq_t *pin_irq(avr_t *avr, struct sim_pin pin)
{
	return avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(pin.port), pin.bit);
}

static void on_pin(struct avr_irq_t *irq, uint32_t v, void *param)
{
	(void)irq;
	struct pins_hook *h = param;
	struct pins *p = h->p;
	struct machine *mc = p->mc;
	int level = v & 1;
	switch (h->kind) {
	case H_STEP: machine_step_pin(mc, h->axis, level, now(p)); break;
	case H_DIR: machine_dir_pin(mc, h->axis, level, now(p)); break;
	case H_ENABLE: machine_enable_pin(mc, level); break;
	case H_SERVO: machine_servo_pin(mc, level, now(p)); break;
	case H_LED:
		if (mc->led != level) {
			mc->led = level;
			mc->changed = 1;
		}
		break;
	}
}

/* a four-wire axis: the whole port after each write, so the four coils of
 * one write arrive as one pattern (no half-written states) */
static void on_coil_port(struct avr_irq_t *irq, uint32_t v, void *param)
{
	(void)irq;
	struct pins_hook *h = param;
	struct pins *p = h->p;
	const struct sim_pin *c = p->board->coil[h->axis];
	int pattern = 0;
	for (int i = 0; i < 4; i++)
		if (v & (1u << c[i].bit))
			pattern |= 1 << i;
	machine_coils(p->mc, h->axis, pattern, now(p));
}

static void hook(struct pins *p, struct sim_pin pin, int kind, int axis)
{
	if (!pin.port)
		return;
	struct pins_hook *h = &p->hooks[p->nhooks++];
	*h = (struct pins_hook){ .p = p, .axis = axis, .kind = kind };
	if (kind == H_COILS)
		avr_irq_register_notify(avr_io_getirq(p->avr, AVR_IOCTL_IOPORT_GETIRQ(pin.port),
						      IOPORT_IRQ_PIN_ALL), on_coil_port, h);
	else
		avr_irq_register_notify(pin_irq(p->avr, pin), on_pin, h);
}

/* Drives (closed switch, pressed button: to ground) or releases an input pin.
 * A released pin reads its internal pull-up, i.e. the PORT bit; without the
 * pull-up it floats and we let it read low, so a missing pull-up shows. */
static void drive(struct pins *p, struct sim_pin pin, int grounded)
{
	if (!pin.port)
		return;
	int port = pin.port - 'A';
	uint8_t mask = (uint8_t)(1u << pin.bit);
	if (grounded)
		p->ext_mask[port] |= mask;
	else
		p->ext_mask[port] &= (uint8_t)~mask;
	p->ext_value[port] &= (uint8_t)~mask; /* a driven pin is always low */
	avr_ioport_external_t ext = {
		.name = (unsigned long)pin.port & 0x7f,
		.mask = p->ext_mask[port],
		.value = p->ext_value[port],
	};
	avr_ioctl(p->avr, AVR_IOCTL_IOPORT_SET_EXTERNAL(pin.port), &ext);
	avr_ioport_state_t st;
	avr_ioctl(p->avr, AVR_IOCTL_IOPORT_GETSTATE(pin.port), &st);
	int level = grounded ? 0 : (st.port >> pin.bit) & 1;
	avr_raise_irq(pin_irq(p->avr, pin), (uint32_t)level);
}

static void on_limit(void *ctx, int axis, int end, int closed)
{
	struct pins *p = ctx;
	const struct board_pins *b = p->board;
	if (b->limit[axis].port) /* one switch per axis: either edge closes it */
		drive(p, b->limit[axis], p->mc->limit_end[axis][0] || p->mc->limit_end[axis][1]);
	else
		drive(p, end ? b->max[axis] : b->min[axis], closed);
	p->mc->changed = 1;
}

int pins_set_button(struct pins *p, int button, int pressed)
{
	if (!p->board->button[button].port)
		return -1;
	p->mc->button[button] = pressed;
	p->mc->changed = 1;
	drive(p, p->board->button[button], pressed);
	return 0;
}

void pins_attach(struct pins *p, avr_t *avr, struct machine *mc, const struct board_pins *b)
{
	p->avr = avr;
	p->mc = mc;
	p->board = b;
	p->nhooks = 0;
	for (int i = 0; i < PINS_PORTS; i++)
		p->ext_mask[i] = p->ext_value[i] = 0;
	for (int a = 0; a < 2; a++) {
		hook(p, b->step[a], H_STEP, a);
		hook(p, b->dir[a], H_DIR, a);
		hook(p, b->coil[a][0], H_COILS, a);
	}
	/* the model has one enable: the first line speaks for both drivers */
	hook(p, b->enable[0], H_ENABLE, 0);
	hook(p, b->servo, H_SERVO, 0);
	hook(p, b->led, H_LED, 0);
	if (b->drive != SIM_STEPDIR)
		mc->enabled = 0; /* coils start off */
	mc->on_limit = on_limit;
	mc->ctx = p;
	/* a carriage started outside the area has its switch closed from power-up */
	for (int axis = 0; axis < 2; axis++)
		for (int end = 0; end < 2; end++)
			if (mc->limit_end[axis][end])
				on_limit(p, axis, end, 1);
}
