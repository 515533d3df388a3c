/* Streaming polyline simplification: keeps a vertex only where the path bends
 * by more than a tolerance (a couple of motor steps: a staircase of steps
 * along a straight move wanders that far from it), so a straight move made
 * of thousands of steps becomes two points. O(1) work and memory per sample. */
#ifndef PATH_SIMPLIFY_H
#define PATH_SIMPLIFY_H

struct path_point {
	double x, y, t;
};

#define PATH_HISTORY 16

struct path_simplify {
	double tol;             /* max distance of dropped samples from the kept segment */
	struct path_point anchor; /* last kept vertex */
	struct path_point cand;   /* latest sample: the end of the open segment */
	struct path_point hist[PATH_HISTORY]; /* latest samples, hist[(head - 1) % N] == cand */
	unsigned head, count;
	int has_wedge;
	double ref, lo, hi;     /* directions (relative to ref) a segment from anchor may take */
	double dmax;            /* farthest accepted sample from the anchor */
};

void path_simplify_start(struct path_simplify *s, double tol, struct path_point p);
/* Feeds one sample. Returns 1 and stores the vertex to keep in *vertex when the
 * path bent before this sample, else 0. */
int path_simplify_add(struct path_simplify *s, struct path_point p, struct path_point *vertex);
/* Ends the open segment at the latest sample (pen change, clear): returns 1
 * with the vertex when the latest sample differs from the anchor. */
int path_simplify_break(struct path_simplify *s, struct path_point *vertex);

#endif
