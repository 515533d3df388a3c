/* model_replay: feeds the machine model (src/machine.c) with pin edges read
 * from a file, without simavr, and prints the trace JSON. For unit tests of
 * the decoder, the kinematics, the checks and the stroke simplification.
 *
 *   model_replay [plotsim model options] EVENTS|-
 * EVENTS: one edge a line, "CYCLE PIN LEVEL", PIN one of sx sy dx dy en servo,
 * cycles at 16 MHz, non-decreasing. Blank lines and '#' comments are skipped. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "machine.h"
#include "options.h"
#include "trace_out.h"

#define CPU_HZ 16000000.0

static int apply(struct machine *mc, const char *pin, int level, unsigned long long cycle)
{
	if (strcmp(pin, "sx") == 0)
		machine_step_pin(mc, AXIS_X, level, cycle);
	else if (strcmp(pin, "sy") == 0)
		machine_step_pin(mc, AXIS_Y, level, cycle);
	else if (strcmp(pin, "dx") == 0)
		machine_dir_pin(mc, AXIS_X, level, cycle);
	else if (strcmp(pin, "dy") == 0)
		machine_dir_pin(mc, AXIS_Y, level, cycle);
	else if (strcmp(pin, "en") == 0)
		machine_enable_pin(mc, level);
	else if (strcmp(pin, "servo") == 0)
		machine_servo_pin(mc, level, cycle);
	else
		return -1;
	return 0;
}

int main(int argc, char **argv)
{
	struct options o;
	char err[512];
	int r = options_parse(argc, argv, &o, err, sizeof err);
	if (r != 0) {
		if (r < 0)
			fprintf(stderr, "model_replay: %s\n", err);
		return r < 0 ? 2 : 0;
	}
	FILE *in = strcmp(o.firmware, "-") == 0 ? stdin : fopen(o.firmware, "r");
	if (!in) {
		perror(o.firmware);
		return 2;
	}
	struct machine_config cfg = {
		.freq = CPU_HZ, .width = o.width, .height = o.height,
		.steps_per_mm = o.steps_per_mm, .corexy = o.corexy,
		.pen_up_us = o.pen_up_us, .pen_down_us = o.pen_down_us,
		.max_step_rate = o.max_step_rate,
	};
	static struct machine mc;
	machine_init(&mc, &cfg, o.start_x, o.start_y);
	char line[256];
	unsigned long long cycle = 0;
	for (int n = 1; fgets(line, sizeof line, in); n++) {
		char pin[16];
		int level;
		if (line[0] == '#' || line[strspn(line, " \t\r\n")] == 0)
			continue;
		if (sscanf(line, "%llu %15s %d", &cycle, pin, &level) != 3 ||
		    apply(&mc, pin, level != 0, cycle) < 0) {
			fprintf(stderr, "model_replay: line %d: cannot read '%s'\n", n, line);
			return 2;
		}
	}
	struct trace_meta meta = { .sim_time = (double)cycle / CPU_HZ, .newline = 1 };
	trace_write_json(stdout, &mc, &meta);
	machine_free(&mc);
	return 0;
}
