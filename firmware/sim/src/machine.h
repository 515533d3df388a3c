/* The plotter's mechanics and the driver checks, fed with pin edges stamped in
 * CPU cycles. Pure logic: no simavr, no I/O, so it is cheap per edge. */
#ifndef MACHINE_H
#define MACHINE_H

#include <stdint.h>

#include "path_simplify.h"
#include "strokes.h"

enum { AXIS_X = 0, AXIS_Y = 1 };
enum { BUTTON_ESTOP = 0, BUTTON_PAUSE = 1, BUTTON_RESUME = 2, BUTTON_COUNT = 3 };

struct machine_config {
	double freq;            /* CPU clock, Hz */
	double width, height;   /* work area, mm */
	double steps_per_mm;
	int corexy;             /* motors a, b: a = x + y, b = x - y */
	double pen_up_us, pen_down_us;
	double max_step_rate;   /* Hz */
	int coil_stride;        /* four-wire drives: sequence states per step (1 half, 2 full) */
};

struct motor {
	int64_t pos;            /* signed position in steps */
	uint64_t pulses;        /* step pulses seen, moving or not */
	int dir, high;          /* dir: the pin level (HIGH = negative at $3=0) */
	uint64_t rise, fall, dir_change, last_step;
	int have_fall, have_step, dir_fresh;
	double max_rate;
	int coils;              /* four-wire: coil pattern (bit0 A .. bit3 D), 0 = off */
	int phase;              /* last energized state 0..7, -1 before the first */
};

struct machine_violations {
	uint64_t short_pulse, dir_setup, step_while_disabled, overspeed;
};

struct machine {
	struct machine_config cfg;
	struct motor m[2];
	int enabled;            /* PB0 low: drivers on */
	int pen_down;
	double pen_us;          /* last servo pulse width */
	uint64_t servo_rise;
	int servo_high;
	int limit[2];           /* any switch of the axis closed */
	int limit_end[2][2];    /* [axis][0 min, 1 max]: outside that edge */
	uint64_t missed_steps;  /* four-wire: illegal phase jumps (a rotor cannot follow) */
	int button[BUTTON_COUNT];
	int led;
	struct path_simplify path;
	struct strokes strokes;
	uint64_t pen_lifts;
	double travel_mm, draw_mm;
	struct machine_violations v;
	uint64_t min_pulse_cycles; /* UINT64_MAX: no pulse yet */
	int changed;            /* something for the trace changed */
	int stepped;            /* a step pulse happened (for last_step_monotonic) */
	void (*on_limit)(void *ctx, int axis, int end, int closed); /* end 0 min, 1 max */
	void *ctx;
};

void machine_init(struct machine *mc, const struct machine_config *cfg, double x0, double y0);
void machine_free(struct machine *mc);
/* forget strokes, distances, counters and extremes; keep position and pins */
void machine_clear(struct machine *mc, uint64_t cycle);

void machine_step_pin(struct machine *mc, int axis, int level, uint64_t cycle);
void machine_dir_pin(struct machine *mc, int axis, int level, uint64_t cycle);
void machine_enable_pin(struct machine *mc, int level);
/* four-wire drives: the axis's coil pattern after a port write (bit0 A .. bit3 D) */
void machine_coils(struct machine *mc, int axis, int pattern, uint64_t cycle);
void machine_servo_pin(struct machine *mc, int level, uint64_t cycle);

void machine_position(const struct machine *mc, double *x, double *y);
/* pen-down distance so far, including the open segment */
double machine_draw_mm(const struct machine *mc);
double machine_travel_mm(const struct machine *mc);

#endif
