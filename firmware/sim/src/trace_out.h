/* The trace as JSON (docs/INTERNALS.md "Virtual plotter") and as SVG. */
#ifndef TRACE_OUT_H
#define TRACE_OUT_H

#include <stdio.h>

#include "machine.h"

struct trace_meta {
	double sim_time;            /* simulated seconds */
	double last_step_monotonic; /* CLOCK_MONOTONIC seconds, 0 before the first step */
	int newline;                /* end with '\n' */
};

void trace_write_json(FILE *f, const struct machine *mc, const struct trace_meta *meta);
void trace_write_svg(FILE *f, const struct machine *mc);

#endif
