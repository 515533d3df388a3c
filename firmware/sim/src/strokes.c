#include "strokes.h"

#include <stdlib.h>

void strokes_init(struct strokes *s)
{
	s->pts = NULL;
	s->starts = NULL;
	s->npts = s->cap = s->nstrokes = s->cap_strokes = 0;
	s->truncated = 0;
}

void strokes_free(struct strokes *s)
{
	free(s->pts);
	free(s->starts);
	strokes_init(s);
}

void strokes_clear(struct strokes *s)
{
	s->npts = s->nstrokes = 0;
	s->truncated = 0;
}

static int reserve_point(struct strokes *s)
{
	if (s->npts >= STROKES_MAX_POINTS) {
		s->truncated = 1;
		return 0;
	}
	if (s->npts == s->cap) {
		size_t cap = s->cap ? s->cap * 2 : 1024;
		struct path_point *p = realloc(s->pts, cap * sizeof *p);
		if (!p) {
			s->truncated = 1;
			return 0;
		}
		s->pts = p;
		s->cap = cap;
	}
	return 1;
}

void strokes_begin(struct strokes *s, struct path_point p)
{
	if (!reserve_point(s))
		return;
	if (s->nstrokes == s->cap_strokes) {
		size_t cap = s->cap_strokes ? s->cap_strokes * 2 : 64;
		size_t *st = realloc(s->starts, cap * sizeof *st);
		if (!st) {
			s->truncated = 1;
			return;
		}
		s->starts = st;
		s->cap_strokes = cap;
	}
	s->starts[s->nstrokes++] = s->npts;
	s->pts[s->npts++] = p;
}

void strokes_append(struct strokes *s, struct path_point p)
{
	if (s->nstrokes == 0 || !reserve_point(s))
		return;
	s->pts[s->npts++] = p;
}

void strokes_get(const struct strokes *s, size_t i, size_t *first, size_t *count)
{
	size_t end = i + 1 < s->nstrokes ? s->starts[i + 1] : s->npts;
	*first = s->starts[i];
	*count = end - s->starts[i];
}
