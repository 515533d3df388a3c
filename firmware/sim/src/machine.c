#include "machine.h"

#include <math.h>
#include <string.h>

/* A4988 timing: 1 us minimum high and low step pulse, 200 ns direction setup. */
#define MIN_PULSE_S 1e-6
#define DIR_SETUP_S 200e-9
/* Pulses outside this range are not servo commands (e.g. a pin glitch). */
#define SERVO_MIN_US 100.0
#define SERVO_MAX_US 5000.0
/* Stroke tolerance: a staircase of steps along a straight move, stepped one
 * motor after the other, strays up to about two steps from the line. */
#define PATH_TOL_STEPS 2.0

void machine_position(const struct machine *mc, double *x, double *y)
{
	double a = (double)mc->m[AXIS_X].pos, b = (double)mc->m[AXIS_Y].pos;
	if (mc->cfg.corexy) {
		*x = (a + b) / 2 / mc->cfg.steps_per_mm;
		*y = (a - b) / 2 / mc->cfg.steps_per_mm;
	} else {
		*x = a / mc->cfg.steps_per_mm;
		*y = b / mc->cfg.steps_per_mm;
	}
}

static struct path_point here(const struct machine *mc, uint64_t cycle)
{
	struct path_point p;
	machine_position(mc, &p.x, &p.y);
	p.t = (double)cycle / mc->cfg.freq;
	return p;
}

static double dist(struct path_point a, struct path_point b)
{
	return hypot(b.x - a.x, b.y - a.y);
}

/* A kept vertex ends a segment that was drawn or travelled. */
static void keep_vertex(struct machine *mc, struct path_point from, struct path_point v)
{
	if (mc->pen_down) {
		mc->draw_mm += dist(from, v);
		strokes_append(&mc->strokes, v);
	} else {
		mc->travel_mm += dist(from, v);
	}
}

static void break_path(struct machine *mc)
{
	struct path_point from = mc->path.anchor, v;
	if (path_simplify_break(&mc->path, &v))
		keep_vertex(mc, from, v);
}

static void update_limits(struct machine *mc)
{
	double x, y;
	machine_position(mc, &x, &y);
	int closed[2][2] = { { x < 0, x > mc->cfg.width }, { y < 0, y > mc->cfg.height } };
	for (int i = 0; i < 2; i++) {
		for (int end = 0; end < 2; end++) {
			if (closed[i][end] != mc->limit_end[i][end]) {
				mc->limit_end[i][end] = closed[i][end];
				if (mc->on_limit)
					mc->on_limit(mc->ctx, i, end, closed[i][end]);
			}
		}
		mc->limit[i] = closed[i][0] || closed[i][1];
	}
}

void machine_init(struct machine *mc, const struct machine_config *cfg, double x0, double y0)
{
	memset(mc, 0, sizeof *mc);
	mc->cfg = *cfg;
	double spm = cfg->steps_per_mm;
	if (cfg->corexy) {
		mc->m[AXIS_X].pos = llround((x0 + y0) * spm);
		mc->m[AXIS_Y].pos = llround((x0 - y0) * spm);
	} else {
		mc->m[AXIS_X].pos = llround(x0 * spm);
		mc->m[AXIS_Y].pos = llround(y0 * spm);
	}
	/* A4988 EN has a pull-down: drivers are on until the pin is driven high. */
	mc->enabled = 1;
	mc->pen_us = 0;
	mc->min_pulse_cycles = UINT64_MAX;
	strokes_init(&mc->strokes);
	path_simplify_start(&mc->path, PATH_TOL_STEPS / spm, here(mc, 0));
	double x, y;
	machine_position(mc, &x, &y);
	mc->limit_end[AXIS_X][0] = x < 0;
	mc->limit_end[AXIS_X][1] = x > cfg->width;
	mc->limit_end[AXIS_Y][0] = y < 0;
	mc->limit_end[AXIS_Y][1] = y > cfg->height;
	mc->limit[AXIS_X] = x < 0 || x > cfg->width;
	mc->limit[AXIS_Y] = y < 0 || y > cfg->height;
	mc->m[AXIS_X].phase = mc->m[AXIS_Y].phase = -1;
	mc->changed = 1;
}

void machine_free(struct machine *mc)
{
	strokes_free(&mc->strokes);
}

void machine_clear(struct machine *mc, uint64_t cycle)
{
	strokes_clear(&mc->strokes);
	path_simplify_start(&mc->path, mc->path.tol, here(mc, cycle));
	if (mc->pen_down)
		strokes_begin(&mc->strokes, mc->path.anchor);
	mc->pen_lifts = 0;
	mc->travel_mm = mc->draw_mm = 0;
	memset(&mc->v, 0, sizeof mc->v);
	mc->missed_steps = 0;
	mc->min_pulse_cycles = UINT64_MAX;
	for (int i = 0; i < 2; i++) {
		mc->m[i].max_rate = 0;
		mc->m[i].pulses = 0;
		mc->m[i].have_step = 0;
	}
	mc->changed = 1;
}

static void move(struct machine *mc, int axis, int delta, uint64_t cycle)
{
	mc->m[axis].pos += delta;
	struct path_point from = mc->path.anchor, v;
	if (path_simplify_add(&mc->path, here(mc, cycle), &v))
		keep_vertex(mc, from, v);
	update_limits(mc);
}

/* a step of either drive kind: its rate, the overspeed check, the counters */
static void count_step(struct machine *mc, struct motor *m, uint64_t cycle)
{
	if (m->have_step && cycle > m->last_step) {
		double rate = mc->cfg.freq / (double)(cycle - m->last_step);
		if (rate > m->max_rate)
			m->max_rate = rate;
		if (rate > mc->cfg.max_step_rate)
			mc->v.overspeed++;
	}
	m->have_step = 1;
	m->last_step = cycle;
	m->pulses++;
	mc->stepped = 1;
	mc->changed = 1;
}

static void step_rise(struct machine *mc, int axis, uint64_t cycle)
{
	struct motor *m = &mc->m[axis];
	double f = mc->cfg.freq;
	if (m->have_fall && (double)(cycle - m->fall) < MIN_PULSE_S * f)
		mc->v.short_pulse++;
	if (m->dir_fresh) {
		m->dir_fresh = 0;
		if ((double)(cycle - m->dir_change) < DIR_SETUP_S * f)
			mc->v.dir_setup++;
	}
	count_step(mc, m, cycle);
	if (!mc->enabled) {
		mc->v.step_while_disabled++;
		return;
	}
	move(mc, axis, m->dir ? -1 : 1, cycle); /* GRBL's convention: a LOW direction pin is positive */
}

void machine_step_pin(struct machine *mc, int axis, int level, uint64_t cycle)
{
	struct motor *m = &mc->m[axis];
	if (level == m->high)
		return;
	m->high = level;
	if (level) {
		m->rise = cycle;
		step_rise(mc, axis, cycle);
		return;
	}
	m->fall = cycle;
	m->have_fall = 1;
	uint64_t width = cycle - m->rise;
	if (width < mc->min_pulse_cycles)
		mc->min_pulse_cycles = width;
	if ((double)width < MIN_PULSE_S * mc->cfg.freq)
		mc->v.short_pulse++;
}

void machine_dir_pin(struct machine *mc, int axis, int level, uint64_t cycle)
{
	struct motor *m = &mc->m[axis];
	if (level == m->dir)
		return;
	m->dir = level;
	m->dir_change = cycle;
	m->dir_fresh = 1;
	/* changed in the same port write as a step edge (simavr reports the
	 * lower pin, the step, first): no setup time at all */
	if (m->high && m->rise == cycle) {
		m->dir_fresh = 0;
		mc->v.dir_setup++;
	}
}

void machine_enable_pin(struct machine *mc, int level)
{
	if (mc->enabled != !level) {
		mc->enabled = !level;
		mc->changed = 1;
	}
}

/* The 8-state sequence A, AB, B, BC, C, CD, D, DA as coil patterns; every
 * other pattern (opposite coils, three or four on) is no state at all. */
static int coil_state(int pattern)
{
	static const int seq[8] = { 1, 3, 2, 6, 4, 12, 8, 9 };
	for (int s = 0; s < 8; s++)
		if (seq[s] == pattern)
			return s;
	return -1;
}

void machine_coils(struct machine *mc, int axis, int pattern, uint64_t cycle)
{
	struct motor *m = &mc->m[axis];
	if (pattern == m->coils)
		return;
	m->coils = pattern;
	mc->changed = 1;
	int any = mc->m[0].coils || mc->m[1].coils;
	mc->enabled = any;
	if (pattern == 0)
		return; /* de-energized: the rotor stays where it is */
	int s = coil_state(pattern);
	if (s < 0) {
		mc->missed_steps++;
		return;
	}
	int stride = mc->cfg.coil_stride > 0 ? mc->cfg.coil_stride : 1;
	if (m->phase >= 0) {
		int d = (s - m->phase + 8) % 8; /* the rotor follows the nearest way */
		int delta = d <= 4 ? d : d - 8;
		if (delta == stride || delta == -stride) {
			count_step(mc, m, cycle);
			move(mc, axis, delta / stride, cycle);
		} else if (delta != 0) {
			/* a jump the rotor cannot follow (opposite state, or two states
			 * at once where one is a step): the motor loses its place */
			mc->missed_steps++;
		}
	}
	m->phase = s;
}

void machine_servo_pin(struct machine *mc, int level, uint64_t cycle)
{
	if (level == mc->servo_high)
		return;
	mc->servo_high = level;
	if (level) {
		mc->servo_rise = cycle;
		return;
	}
	double us = (double)(cycle - mc->servo_rise) * 1e6 / mc->cfg.freq;
	if (us < SERVO_MIN_US || us > SERVO_MAX_US)
		return;
	if (fabs(us - mc->pen_us) >= 0.5)
		mc->changed = 1;
	mc->pen_us = us;
	int down = fabs(us - mc->cfg.pen_down_us) < fabs(us - mc->cfg.pen_up_us);
	if (down == mc->pen_down)
		return;
	break_path(mc);
	mc->path.anchor.t = mc->path.cand.t = (double)cycle / mc->cfg.freq;
	if (down) {
		mc->pen_down = 1;
		strokes_begin(&mc->strokes, mc->path.anchor);
	} else {
		mc->pen_down = 0;
		mc->pen_lifts++;
	}
	mc->changed = 1;
}

double machine_draw_mm(const struct machine *mc)
{
	double open = dist(mc->path.anchor, mc->path.cand);
	return mc->draw_mm + (mc->pen_down ? open : 0);
}

double machine_travel_mm(const struct machine *mc)
{
	double open = dist(mc->path.anchor, mc->path.cand);
	return mc->travel_mm + (mc->pen_down ? 0 : open);
}
