/* Pen-down strokes: polylines of (x, y, t) kept in one growable point array
 * with a hard cap, so a runaway job cannot exhaust memory. */
#ifndef STROKES_H
#define STROKES_H

#include <stddef.h>

#include "path_simplify.h"

#define STROKES_MAX_POINTS 4000000u

struct strokes {
	struct path_point *pts;
	size_t npts, cap;
	size_t *starts;          /* index of each stroke's first point */
	size_t nstrokes, cap_strokes;
	int truncated;           /* points were dropped at the cap */
};

void strokes_init(struct strokes *s);
void strokes_free(struct strokes *s);
void strokes_clear(struct strokes *s);
void strokes_begin(struct strokes *s, struct path_point p);
void strokes_append(struct strokes *s, struct path_point p);
/* points of stroke i: pts[first .. first + count) */
void strokes_get(const struct strokes *s, size_t i, size_t *first, size_t *count);

#endif
