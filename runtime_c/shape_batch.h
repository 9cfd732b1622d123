/* Many rays, or many points, of one shape in one call: what `implgen mesh` asks of a shape (every grid line is
 * a ray; every crossing point needs f and its gradient). One call costs n solves in C, not n calls from Python.
 * Pointers must not be NULL (params may be NULL when the shape has none); arrays hold n entries each
 * (3 n for points and directions, n * IG_MAX_DEGREE for roots). No state is kept between calls. */
#ifndef IMPLGEN_SHAPE_BATCH_H
#define IMPLGEN_SHAPE_BATCH_H

#include "shape.h"

/* For each ray i: every distinct root of f(o_i + t d_i) in [tmin_i, tmax_i], ascending, what ig_shape_roots
 * gives bit for bit, into roots[i * IG_MAX_DEGREE ...], and their count into counts[i]. */
void ig_shape_roots_many(const ig_shape *shape, const double *params, long n, const double *o, const double *d,
                         const double *tmin, const double *tmax, ig_root_method method, double *roots, int *counts);

/* For each point i: f(p_i) into f[i] and grad f(p_i) into g[3 i ...] (g may be NULL: values only); NaN where
 * the shape has no value or gradient function. */
void ig_shape_eval_many(const ig_shape *shape, const double *params, long n, const double *p, double *f, double *g);

/* f at every point (x[i], y[j], z[k]) of a grid into f[(i * ny + j) * nz + k] (C order): a grid's values
 * without an array of its points. */
void ig_shape_values_grid(const ig_shape *shape, const double *params, const double *x, long nx, const double *y,
                          long ny, const double *z, long nz, double *f);

/* Each point p_i moved onto f = 0 by Newton steps of least norm, p += -f grad f / |grad f|^2, at most `steps` of
 * them, in place. ok[i] = 1 when it converged -- a step of at most `tol`, or a step at most `noise` that did not
 * halve the one before (f's rounding), or a last step at most `noise` -- and moved at most `reach` along each
 * axis; 0 otherwise, and when a step is not finite (the point is left where that step would have started). */
void ig_shape_project_many(const ig_shape *shape, const double *params, long n, double *p, int steps, double tol,
                           double noise, double reach, unsigned char *ok);

#endif
