/* plotsim's command line (docs/INTERNALS.md "Virtual plotter"). */
#ifndef OPTIONS_H
#define OPTIONS_H

#include <stddef.h>

struct options {
	const char *firmware;
	const char *pty_link, *trace, *control, *eeprom;
	double speed;            /* 0: unthrottled */
	double width, height, steps_per_mm;
	int corexy;
	double start_x, start_y;
	double pen_up_us, pen_down_us;
	double max_step_rate;
	const char *bootloader;  /* HEX: start in this bootloader, flash otherwise erased */
	const char *board;       /* board profile name (default uno-cnc-shield) */
	int have_spm, have_width, have_height; /* given on the command line */
};

/* 0: ok; 1: --help printed; -1: error message in err */
int options_parse(int argc, char **argv, struct options *o, char *err, size_t errlen);
extern const char options_usage[];

#endif
