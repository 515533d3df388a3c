/* The CNC shield wiring (DESIGN.md pin map) between simavr's I/O ports and the
 * machine model: output pins feed the model on change only; the limit
 * switches and buttons drive input pins. */
#ifndef PINS_H
#define PINS_H

#include "machine.h"
#include "sim_avr.h"

struct pins {
	avr_t *avr;
	struct machine *mc;
	uint8_t ext_mask[2], ext_value[2]; /* externally driven pins of ports B, C */
};

void pins_attach(struct pins *p, avr_t *avr, struct machine *mc);
/* button: BUTTON_ESTOP..BUTTON_RESUME; pressed pulls the pin to ground */
void pins_set_button(struct pins *p, int button, int pressed);

#endif
