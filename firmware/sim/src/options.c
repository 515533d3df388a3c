#include "options.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char options_usage[] =
	"usage: plotsim [options] FIRMWARE.elf\n"
	"  --pty-link PATH        symlink PATH -> the pty\n"
	"  --speed X              X times real time (default 1); 0 = unthrottled\n"
	"  --trace FILE           JSON trace, kept current\n"
	"  --control PATH         Unix socket for control commands\n"
	"  --eeprom FILE          EEPROM image (blank if missing), saved on change\n"
	"  --board NAME           board profile (wiring, chip; default uno-cnc-shield)\n"
	"  --bootloader HEX       run this bootloader from reset on an erased flash\n"
	"                         (no FIRMWARE.elf: flash it over the pty with avrdude)\n"
	"  --width MM --height MM work area (default: the board's, 300 220)\n"
	"  --steps-per-mm N       (default: the board's, 80)\n"
	"  --corexy               CoreXY kinematics\n"
	"  --start X,Y            carriage position at start, mm (default 0,0)\n"
	"  --pen-up-us N --pen-down-us N  servo pulse widths (default 1000 2000)\n"
	"  --max-step-rate HZ     overspeed threshold (default 40000)\n"
	"Control socket commands, one a line: press NAME, release NAME (estop, pause,\n"
	"resume), trace, svg PATH, clear, quit. See docs/INTERNALS.md.\n";

enum {
	OPT_PTY = 256, OPT_SPEED, OPT_TRACE, OPT_CONTROL, OPT_EEPROM, OPT_WIDTH, OPT_HEIGHT,
	OPT_SPM, OPT_COREXY, OPT_START, OPT_PEN_UP, OPT_PEN_DOWN, OPT_MAX_RATE, OPT_HELP, OPT_BOARD, OPT_BOOTLOADER,
};

static const struct option longopts[] = {
	{ "pty-link", required_argument, NULL, OPT_PTY },
	{ "speed", required_argument, NULL, OPT_SPEED },
	{ "trace", required_argument, NULL, OPT_TRACE },
	{ "control", required_argument, NULL, OPT_CONTROL },
	{ "eeprom", required_argument, NULL, OPT_EEPROM },
	{ "width", required_argument, NULL, OPT_WIDTH },
	{ "height", required_argument, NULL, OPT_HEIGHT },
	{ "steps-per-mm", required_argument, NULL, OPT_SPM },
	{ "corexy", no_argument, NULL, OPT_COREXY },
	{ "start", required_argument, NULL, OPT_START },
	{ "pen-up-us", required_argument, NULL, OPT_PEN_UP },
	{ "pen-down-us", required_argument, NULL, OPT_PEN_DOWN },
	{ "max-step-rate", required_argument, NULL, OPT_MAX_RATE },
	{ "help", no_argument, NULL, OPT_HELP },
	{ "board", required_argument, NULL, OPT_BOARD },
	{ "bootloader", required_argument, NULL, OPT_BOOTLOADER },
	{ NULL, 0, NULL, 0 },
};

/* a finite number in [lo, hi], the whole argument */
static int number(const char *s, double lo, double hi, double *out)
{
	char *end;
	double v = strtod(s, &end);
	if (end == s || *end || !isfinite(v) || v < lo || v > hi)
		return -1;
	*out = v;
	return 0;
}

int options_parse(int argc, char **argv, struct options *o, char *err, size_t errlen)
{
	*o = (struct options){
		.speed = 1, .width = 300, .height = 220, .steps_per_mm = 80,
		.pen_up_us = 1000, .pen_down_us = 2000, .max_step_rate = 40000,
		.board = "uno-cnc-shield",
	};
	opterr = 0;
	int c;
	while ((c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
		const char *name = longopts[0].name;
		for (const struct option *lo = longopts; lo->name; lo++)
			if (lo->val == c)
				name = lo->name;
		int bad = 0;
		switch (c) {
		case OPT_PTY: o->pty_link = optarg; break;
		case OPT_TRACE: o->trace = optarg; break;
		case OPT_CONTROL: o->control = optarg; break;
		case OPT_EEPROM: o->eeprom = optarg; break;
		case OPT_COREXY: o->corexy = 1; break;
		case OPT_SPEED: bad = number(optarg, 0, 1e6, &o->speed); break;
		case OPT_BOARD: o->board = optarg; break;
		case OPT_BOOTLOADER: o->bootloader = optarg; break;
		case OPT_WIDTH: bad = number(optarg, 1, 1e5, &o->width); o->have_width = 1; break;
		case OPT_HEIGHT: bad = number(optarg, 1, 1e5, &o->height); o->have_height = 1; break;
		case OPT_SPM: bad = number(optarg, 0.01, 1e5, &o->steps_per_mm); o->have_spm = 1; break;
		case OPT_PEN_UP: bad = number(optarg, 100, 5000, &o->pen_up_us); break;
		case OPT_PEN_DOWN: bad = number(optarg, 100, 5000, &o->pen_down_us); break;
		case OPT_MAX_RATE: bad = number(optarg, 1, 1e7, &o->max_step_rate); break;
		case OPT_START: {
			char buf[64];
			char *comma;
			snprintf(buf, sizeof buf, "%s", optarg);
			comma = strchr(buf, ',');
			if (!comma) {
				bad = -1;
				break;
			}
			*comma = 0;
			bad = number(buf, -1e5, 1e5, &o->start_x) ||
			      number(comma + 1, -1e5, 1e5, &o->start_y);
			break;
		}
		case OPT_HELP:
			fputs(options_usage, stdout);
			return 1;
		default:
			snprintf(err, errlen, "unknown or incomplete option '%s'", argv[optind - 1]);
			return -1;
		}
		if (bad) {
			snprintf(err, errlen, "--%s: invalid value '%s'", name, optarg);
			return -1;
		}
	}
	if (o->pen_up_us == o->pen_down_us) {
		snprintf(err, errlen, "--pen-up-us and --pen-down-us must differ");
		return -1;
	}
	if (o->bootloader && optind == argc)
		return 0; /* the bootloader is the program */
	if (optind != argc - 1) {
		snprintf(err, errlen, optind >= argc ? "missing FIRMWARE.elf" : "more than one firmware given");
		return -1;
	}
	o->firmware = argv[optind];
	return 0;
}
