/* The wiring of each board profile, read from the firmware's own board
 * headers (../../src/boards/NAME.h): board_pins.c is compiled once per
 * board, so a pin is still named in one place only. */
#ifndef BOARD_PINS_H
#define BOARD_PINS_H

struct sim_pin {
	char port;   /* 'A'..'L'; 0: the board has no such pin */
	int bit;
};

enum { SIM_STEPDIR = 1, SIM_UNIPOLAR = 2, SIM_BIPOLAR = 3 };

struct board_pins {
	const char *name, *mcu;
	int drive;                      /* SIM_* */
	int coil_stride;                /* four-wire: 1 half step, 2 full step */
	struct sim_pin step[2], dir[2], enable[2];
	struct sim_pin coil[2][4];      /* A, B, C, D in sequence order */
	struct sim_pin limit[2];        /* one switch per axis, closed at either edge */
	struct sim_pin min[2], max[2];  /* or a switch at each end */
	struct sim_pin button[3];       /* estop, pause, resume */
	struct sim_pin led, servo;
	double steps_per_mm, width, height;
	long baud;
};

/* NULL for an unknown name */
const struct board_pins *board_pins_find(const char *name);
extern const char board_pins_names[]; /* "a, b, c" for messages */

#endif
