#include "path_simplify.h"

#include <math.h>

static double wrap_angle(double a)
{
	while (a > M_PI)
		a -= 2 * M_PI;
	while (a <= -M_PI)
		a += 2 * M_PI;
	return a;
}

static void restart(struct path_simplify *s, struct path_point p)
{
	s->anchor = p;
	s->cand = p;
	s->prev = p;
	s->has_wedge = 0;
	s->dmax = 0;
}

void path_simplify_start(struct path_simplify *s, double tol, struct path_point p)
{
	s->tol = tol;
	s->back_tol = tol / 2;
	restart(s, p);
}

/* Tries to extend the open segment to p; 0 when p lies off the sleeve. */
static int extend(struct path_simplify *s, struct path_point p)
{
	double dx = p.x - s->anchor.x, dy = p.y - s->anchor.y;
	double d = hypot(dx, dy);
	if (d <= s->tol) {
		/* too close to the anchor to constrain the direction, but a sample
		 * that comes back towards it after going farther is a reversal */
		if (d < s->dmax - s->back_tol)
			return 0;
		s->prev = s->cand;
		s->cand = p;
		return 1;
	}
	double half = asin(s->tol / d);
	double angle = atan2(dy, dx);
	if (!s->has_wedge) {
		s->has_wedge = 1;
		s->ref = angle;
		s->lo = -half;
		s->hi = half;
	} else {
		double rel = wrap_angle(angle - s->ref);
		if (rel < s->lo || rel > s->hi || d < s->dmax - s->back_tol)
			return 0;
		if (rel - half > s->lo)
			s->lo = rel - half;
		if (rel + half < s->hi)
			s->hi = rel + half;
	}
	if (d > s->dmax)
		s->dmax = d;
	s->prev = s->cand;
	s->cand = p;
	return 1;
}

int path_simplify_add(struct path_simplify *s, struct path_point p, struct path_point *vertex)
{
	if (extend(s, p))
		return 0;
	/* The bend is at cand or, when cand already left the straight line
	 * (a corner: the first step of the new direction still fitted the
	 * sleeve), at the sample before it. */
	struct path_point a = s->anchor, b = s->prev, c = s->cand;
	double len = hypot(b.x - a.x, b.y - a.y);
	double off = len > 0 ? fabs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)) / len : 0;
	if (len > 0 && off > s->tol / 2) {
		*vertex = b;
		restart(s, b);
		extend(s, c);
	} else {
		*vertex = c;
		restart(s, c);
	}
	/* from the new anchor the sample fits: it is at most two steps away */
	extend(s, p);
	return 1;
}

int path_simplify_break(struct path_simplify *s, struct path_point *vertex)
{
	int moved = s->cand.x != s->anchor.x || s->cand.y != s->anchor.y;
	*vertex = s->cand;
	restart(s, s->cand);
	return moved;
}
