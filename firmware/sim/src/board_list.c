/* The boards plotsim knows: one compiled board_pins.c each (Makefile). */
#include <string.h>

#include "board_pins.h"

extern const struct board_pins board_uno_cnc_shield, board_uno_uln2003, board_mega_l298n,
	board_mega_stepdir, board_mega_ramps14;

static const struct board_pins *const boards[] = {
	&board_uno_cnc_shield, &board_uno_uln2003, &board_mega_l298n, &board_mega_stepdir,
	&board_mega_ramps14,
};

const char board_pins_names[] =
	"uno-cnc-shield, uno-uln2003, mega-l298n, mega-stepdir, mega-ramps14";

const struct board_pins *board_pins_find(const char *name)
{
	for (size_t i = 0; i < sizeof boards / sizeof boards[0]; i++)
		if (strcmp(boards[i]->name, name) == 0)
			return boards[i];
	return NULL;
}
