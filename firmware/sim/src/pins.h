/* A board's wiring (board_pins.h) between simavr's I/O ports and the
 * machine model: output pins feed the model on change only; the limit
 * switches and buttons drive input pins. */
#ifndef PINS_H
#define PINS_H

#include "board_pins.h"
#include "machine.h"
#include "sim_avr.h"

#define PINS_PORTS 12 /* 'A'..'L' */

struct pins {
	avr_t *avr;
	struct machine *mc;
	const struct board_pins *board;
	uint8_t ext_mask[PINS_PORTS], ext_value[PINS_PORTS]; /* externally driven pins */
	struct pins_hook {
		struct pins *p;
		int axis;       /* coil port hooks */
		int kind;
	} hooks[16];
	int nhooks;
};

void pins_attach(struct pins *p, avr_t *avr, struct machine *mc, const struct board_pins *board);
/* button: BUTTON_ESTOP..BUTTON_RESUME; pressed pulls the pin to ground.
 * -1 if the board has no such button. */
int pins_set_button(struct pins *p, int button, int pressed);

#endif
