/* What a generated algebraic shape offers the runtime, and the ray/shape intersection that uses it.
 *
 * Every generated <name>.c defines `const ig_shape <name>_shape` (read-only, no mutable globals) and the
 * functions below it points to. Inside is f < 0, outside f > 0; the outward normal is grad f / |grad f|.
 * Ray directions are NOT assumed to be unit length. Parameters are passed in the order the spec declares.
 */
#ifndef IMPLGEN_SHAPE_H
#define IMPLGEN_SHAPE_H

#include "roots.h"

typedef struct ig_shape {
    const char *name;
    int degree;   /* total degree of f in x, y, z */
    int nparams;
    /* c[0..degree] of f(o + t d), lowest power first */
    void (*coeffs)(const double o[3], const double d[3], const double *params, double *c);
    double (*value)(const double p[3], const double *params);
    void (*gradient)(const double p[3], const double *params, double g[3]);
    /* Object-space box {xmin, ymin, zmin, xmax, ymax, zmax}; an axis the spec leaves open is +-INFINITY.
     * Returns 1 when the spec gives bounds, 0 when the shape is unbounded (box then all +-INFINITY). */
    int (*bounds)(const double *params, double box[6]);
} ig_shape;

/* All distinct roots of f(o + t d) in [tmin, tmax], ascending; returns the count (<= shape->degree).
 * Clips [tmin, tmax] to the shape's box first; computes the coefficients at a shifted origin o' = o + ts d
 * close to the object (the clipped interval's point closest to the box centre, or to the coordinate origin
 * for an unbounded shape), solves in the shifted parameter and shifts back, so a far-away ray loses nothing
 * to cancellation. roots[] needs room for IG_MAX_DEGREE entries. */
int ig_shape_roots(const ig_shape *shape, const double *params, const double o[3], const double d[3],
                   double tmin, double tmax, ig_root_method method, double *roots);

/* The nearest of those roots (what ig_shape_roots would list first) into *t: 1, or 0 when there is none.
 * The same clip and shift; the solver stops at the first root instead of isolating all (ig_first_root). */
int ig_shape_first_root(const ig_shape *shape, const double *params, const double o[3], const double d[3],
                        double tmin, double tmax, ig_root_method method, double *t);

/* Unit outward normal at p. At a singular point (grad f = 0 or not finite, e.g. a cone's apex) writes
 * (0, 0, 0) and returns 0 -- never NaN; the caller picks a fallback (e.g. facing the ray). Returns 1 otherwise. */
int ig_shape_normal(const ig_shape *shape, const double *params, const double p[3], double n[3]);

#endif
