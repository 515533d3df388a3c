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
	s->head = s->count = 0;
	s->has_wedge = 0;
	s->dmax = 0;
}

void path_simplify_start(struct path_simplify *s, double tol, struct path_point p)
{
	s->tol = tol;
	restart(s, p);
}

static void remember(struct path_simplify *s, struct path_point p)
{
	s->cand = p;
	s->hist[s->head] = p;
	s->head = (s->head + 1) % PATH_HISTORY;
	if (s->count < PATH_HISTORY)
		s->count++;
}

/* Tries to extend the open segment to p (sleeve / cone intersection):
 * 0 when a segment from the anchor to p would leave an earlier sample more
 * than tol away, or when p goes back towards the anchor. */
static int extend(struct path_simplify *s, struct path_point p)
{
	double dx = p.x - s->anchor.x, dy = p.y - s->anchor.y;
	double d = hypot(dx, dy);
	if (d < s->dmax - s->tol / 2)
		return 0;
	if (d > s->tol) {
		double half = asin(s->tol / d);
		double angle = atan2(dy, dx);
		if (!s->has_wedge) {
			s->has_wedge = 1;
			s->ref = angle;
			s->lo = -half;
			s->hi = half;
		} else {
			double rel = wrap_angle(angle - s->ref);
			if (rel < s->lo || rel > s->hi)
				return 0;
			if (rel - half > s->lo)
				s->lo = rel - half;
			if (rel + half < s->hi)
				s->hi = rel + half;
		}
	}
	if (d > s->dmax)
		s->dmax = d;
	remember(s, p);
	return 1;
}

static double dist_to_segment(struct path_point p, struct path_point a, struct path_point b)
{
	double vx = b.x - a.x, vy = b.y - a.y, wx = p.x - a.x, wy = p.y - a.y;
	double len2 = vx * vx + vy * vy;
	double u = len2 > 0 ? (wx * vx + wy * vy) / len2 : 0;
	if (u < 0)
		u = 0;
	if (u > 1)
		u = 1;
	return hypot(wx - u * vx, wy - u * vy);
}

int path_simplify_add(struct path_simplify *s, struct path_point p, struct path_point *vertex)
{
	if (extend(s, p))
		return 0;
	/* The bend is not where it was noticed but up to a few samples earlier
	 * (samples after a corner still fit the sleeve for a while): keep the
	 * recent sample farthest from the straight anchor -> cand segment. */
	unsigned n = s->count, best = 0;
	if (n == 0) /* cannot happen: the first sample is a step from the anchor */
		n = 1, s->hist[(s->head + PATH_HISTORY - 1) % PATH_HISTORY] = s->cand;
	double best_d = -1;
	struct path_point recent[PATH_HISTORY];
	for (unsigned i = 0; i < n; i++) {
		recent[i] = s->hist[(s->head + PATH_HISTORY - n + i) % PATH_HISTORY];
		double d = dist_to_segment(recent[i], s->anchor, s->cand);
		if (d > best_d) {
			best_d = d;
			best = i;
		}
	}
	*vertex = recent[best];
	restart(s, recent[best]);
	for (unsigned i = best + 1; i < n; i++)
		if (!extend(s, recent[i]))
			remember(s, recent[i]); /* within a few steps of the vertex anyway */
	if (!extend(s, p))
		remember(s, p);
	return 1;
}

int path_simplify_break(struct path_simplify *s, struct path_point *vertex)
{
	int moved = s->cand.x != s->anchor.x || s->cand.y != s->anchor.y;
	*vertex = s->cand;
	restart(s, s->cand);
	return moved;
}
