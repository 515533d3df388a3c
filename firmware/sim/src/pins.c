#include "pins.h"

#include "avr_ioport.h"

enum { PORT_B = 0, PORT_C = 1 };

/* Pin map: step PD2/PD3, dir PD5/PD6, enable PB0, limits PB1/PB2, servo PB3,
 * buttons PC0 (stop) PC1 (pause) PC2 (resume), stop LED PC3. */
#define PIN_LIMIT_X 1
#define PIN_LIMIT_Y 2
#define PIN_LED 3

static uint64_t now(struct pins *p)
{
	return p->avr->cycle;
}

static void on_step_x(struct avr_irq_t *irq, uint32_t v, void *param)
{
	(void)irq;
	struct pins *p = param;
	machine_step_pin(p->mc, AXIS_X, v & 1, now(p));
}

static void on_step_y(struct avr_irq_t *irq, uint32_t v, void *param)
{
	(void)irq;
	struct pins *p = param;
	machine_step_pin(p->mc, AXIS_Y, v & 1, now(p));
}

static void on_dir_x(struct avr_irq_t *irq, uint32_t v, void *param)
{
	(void)irq;
	struct pins *p = param;
	machine_dir_pin(p->mc, AXIS_X, v & 1, now(p));
}

static void on_dir_y(struct avr_irq_t *irq, uint32_t v, void *param)
{
	(void)irq;
	struct pins *p = param;
	machine_dir_pin(p->mc, AXIS_Y, v & 1, now(p));
}

static void on_enable(struct avr_irq_t *irq, uint32_t v, void *param)
{
	(void)irq;
	struct pins *p = param;
	machine_enable_pin(p->mc, v & 1);
}

static void on_servo(struct avr_irq_t *irq, uint32_t v, void *param)
{
	(void)irq;
	struct pins *p = param;
	machine_servo_pin(p->mc, v & 1, now(p));
}

static void on_led(struct avr_irq_t *irq, uint32_t v, void *param)
{
	(void)irq;
	struct pins *p = param;
	if (p->mc->led != (int)(v & 1)) {
		p->mc->led = v & 1;
		p->mc->changed = 1;
	}
}

static avr_irq_t *pin_irq(avr_t *avr, char port, int bit)
{
	return avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(port), bit);
}

/* Drives (closed switch, pressed button: to ground) or releases an input pin.
 * A released pin reads its internal pull-up, i.e. the PORT bit; without the
 * pull-up it floats and we let it read low, so a missing pull-up shows. */
static void drive(struct pins *p, int port, int bit, int grounded)
{
	char name = port == PORT_B ? 'B' : 'C';
	uint8_t mask = (uint8_t)(1u << bit);
	if (grounded)
		p->ext_mask[port] |= mask;
	else
		p->ext_mask[port] &= (uint8_t)~mask;
	p->ext_value[port] &= (uint8_t)~mask; /* a driven pin is always low */
	avr_ioport_external_t ext = {
		.name = (unsigned long)name & 0x7f,
		.mask = p->ext_mask[port],
		.value = p->ext_value[port],
	};
	avr_ioctl(p->avr, AVR_IOCTL_IOPORT_SET_EXTERNAL(name), &ext);
	avr_ioport_state_t st;
	avr_ioctl(p->avr, AVR_IOCTL_IOPORT_GETSTATE(name), &st);
	int level = grounded ? 0 : (st.port >> bit) & 1;
	avr_raise_irq(pin_irq(p->avr, name, bit), (uint32_t)level);
}

static void on_limit(void *ctx, int axis, int closed)
{
	struct pins *p = ctx;
	drive(p, PORT_B, axis == AXIS_X ? PIN_LIMIT_X : PIN_LIMIT_Y, closed);
	p->mc->changed = 1;
}

void pins_set_button(struct pins *p, int button, int pressed)
{
	p->mc->button[button] = pressed;
	p->mc->changed = 1;
	drive(p, PORT_C, button, pressed);
}

void pins_attach(struct pins *p, avr_t *avr, struct machine *mc)
{
	p->avr = avr;
	p->mc = mc;
	p->ext_mask[PORT_B] = p->ext_mask[PORT_C] = 0;
	p->ext_value[PORT_B] = p->ext_value[PORT_C] = 0;
	avr_irq_register_notify(pin_irq(avr, 'D', 2), on_step_x, p);
	avr_irq_register_notify(pin_irq(avr, 'D', 3), on_step_y, p);
	avr_irq_register_notify(pin_irq(avr, 'D', 5), on_dir_x, p);
	avr_irq_register_notify(pin_irq(avr, 'D', 6), on_dir_y, p);
	avr_irq_register_notify(pin_irq(avr, 'B', 0), on_enable, p);
	avr_irq_register_notify(pin_irq(avr, 'B', 3), on_servo, p);
	avr_irq_register_notify(pin_irq(avr, 'C', PIN_LED), on_led, p);
	mc->on_limit = on_limit;
	mc->ctx = p;
	/* a carriage started outside the area has its switch closed from power-up */
	for (int axis = 0; axis < 2; axis++)
		if (mc->limit[axis])
			on_limit(p, axis, 1);
}
