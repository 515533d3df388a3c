#include "trace_out.h"

/* Strokes with the open segment's end appended while the pen is down, so the
 * trace shows what is drawn up to now, not only up to the last bend. */
typedef void (*point_fn)(FILE *f, struct path_point p, int first);

static void each_stroke(FILE *f, const struct machine *mc, point_fn point,
			const char *open, const char *close, const char *sep)
{
	const struct strokes *s = &mc->strokes;
	for (size_t i = 0; i < s->nstrokes; i++) {
		size_t first, count;
		strokes_get(s, i, &first, &count);
		fputs(i ? sep : "", f);
		fputs(open, f);
		for (size_t k = 0; k < count; k++)
			point(f, s->pts[first + k], k == 0);
		int last = i + 1 == s->nstrokes;
		struct path_point end = mc->path.cand;
		struct path_point prev = s->pts[first + count - 1];
		if (last && mc->pen_down && (end.x != prev.x || end.y != prev.y))
			point(f, end, 0);
		fputs(close, f);
	}
}

static void json_point(FILE *f, struct path_point p, int first)
{
	fprintf(f, "%s[%.4f,%.4f,%.6f]", first ? "" : ",", p.x, p.y, p.t);
}

void trace_write_json(FILE *f, const struct machine *mc, const struct trace_meta *meta)
{
	double x, y;
	machine_position(mc, &x, &y);
	fprintf(f, "{\"sim_time\":%.6f,\"position\":{\"x\":%.4f,\"y\":%.4f},", meta->sim_time, x, y);
	fprintf(f, "\"pen\":\"%s\",\"pen_us\":%.1f,\"enabled\":%s,", mc->pen_down ? "down" : "up",
		mc->pen_us, mc->enabled ? "true" : "false");
	fprintf(f, "\"limits\":{\"x\":%s,\"y\":%s},", mc->limit[AXIS_X] ? "true" : "false",
		mc->limit[AXIS_Y] ? "true" : "false");
	fprintf(f, "\"buttons\":{\"estop\":%s,\"pause\":%s,\"resume\":%s},\"led\":%s,",
		mc->button[BUTTON_ESTOP] ? "true" : "false",
		mc->button[BUTTON_PAUSE] ? "true" : "false",
		mc->button[BUTTON_RESUME] ? "true" : "false", mc->led ? "true" : "false");
	fprintf(f, "\"steps\":{\"x\":%lld,\"y\":%lld},\"pulses\":{\"x\":%llu,\"y\":%llu},",
		(long long)mc->m[AXIS_X].pos, (long long)mc->m[AXIS_Y].pos,
		(unsigned long long)mc->m[AXIS_X].pulses, (unsigned long long)mc->m[AXIS_Y].pulses);
	fprintf(f, "\"limit_ends\":{\"x_min\":%s,\"x_max\":%s,\"y_min\":%s,\"y_max\":%s},",
		mc->limit_end[0][0] ? "true" : "false", mc->limit_end[0][1] ? "true" : "false",
		mc->limit_end[1][0] ? "true" : "false", mc->limit_end[1][1] ? "true" : "false");
	fprintf(f, "\"dir_pins\":{\"x\":%d,\"y\":%d},", mc->m[0].dir, mc->m[1].dir);
	fprintf(f, "\"coils\":{\"x\":%d,\"y\":%d},\"missed_steps\":%llu,", mc->m[0].coils,
		mc->m[1].coils, (unsigned long long)mc->missed_steps);
	fputs("\"strokes\":[", f);
	each_stroke(f, mc, json_point, "[", "]", ",");
	fprintf(f, "],\"strokes_truncated\":%s,", mc->strokes.truncated ? "true" : "false");
	fprintf(f, "\"pen_lifts\":%llu,\"travel_mm\":%.4f,\"draw_mm\":%.4f,",
		(unsigned long long)mc->pen_lifts, machine_travel_mm(mc), machine_draw_mm(mc));
	fprintf(f, "\"violations\":{\"short_pulse\":%llu,\"dir_setup\":%llu,"
		"\"step_while_disabled\":%llu,\"overspeed\":%llu},",
		(unsigned long long)mc->v.short_pulse, (unsigned long long)mc->v.dir_setup,
		(unsigned long long)mc->v.step_while_disabled,
		(unsigned long long)mc->v.overspeed);
	if (mc->min_pulse_cycles == UINT64_MAX)
		fputs("\"min_pulse_us\":null,", f);
	else
		fprintf(f, "\"min_pulse_us\":%.4f,",
			(double)mc->min_pulse_cycles * 1e6 / mc->cfg.freq);
	fprintf(f, "\"max_step_rate\":{\"x\":%.1f,\"y\":%.1f},", mc->m[AXIS_X].max_rate,
		mc->m[AXIS_Y].max_rate);
	if (meta->last_step_monotonic > 0)
		fprintf(f, "\"last_step_monotonic\":%.6f}", meta->last_step_monotonic);
	else
		fputs("\"last_step_monotonic\":null}", f);
	if (meta->newline)
		fputc('\n', f);
}

static void svg_point(FILE *f, struct path_point p, int first)
{
	fprintf(f, "%s%.3f,%.3f", first ? "" : " ", p.x, p.y);
}

void trace_write_svg(FILE *f, const struct machine *mc)
{
	double w = mc->cfg.width, h = mc->cfg.height;
	fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
		"<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.3fmm\" height=\"%.3fmm\" "
		"viewBox=\"0 0 %.3f %.3f\">\n", w, h, w, h);
	/* machine Y points away from the operator: flip so the drawing reads as on paper */
	fprintf(f, "<rect x=\"0\" y=\"0\" width=\"%.3f\" height=\"%.3f\" fill=\"white\" "
		"stroke=\"#ccc\" stroke-width=\"0.2\"/>\n"
		"<g transform=\"matrix(1 0 0 -1 0 %.3f)\" fill=\"none\" stroke=\"black\" "
		"stroke-width=\"0.3\" stroke-linecap=\"round\" stroke-linejoin=\"round\">\n", w, h, h);
	each_stroke(f, mc, svg_point, "<polyline points=\"", "\"/>\n", "");
	fputs("</g>\n</svg>\n", f);
}
