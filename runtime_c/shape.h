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
    int degree; /* total degree of f in x, y, z */
    int nparams;
    /* c[0..degree] of f(o + t d), lowest power first */
    void (*coeffs)(const double o[3], const double d[3], const double *params, double *c);
    double (*value)(const double p[3], const double *params);
    void (*gradient)(const double p[3], const double *params, double g[3]);
    /* Object-space box {xmin, ymin, zmin, xmax, ymax, zmax}; an axis the spec leaves open is +-INFINITY.
     * Returns 1 when the spec gives bounds, 0 when the shape is unbounded (box then all +-INFINITY). */
    int (*bounds)(const double *params, double box[6]);
    /* The coefficients again, each with a rigorous bound e[k] on its error, for an origin and a direction known
     * within eo and ed componentwise (docs/certify.md); returns 0 when it has no bound. NULL in a hand-made
     * shape: its rays are never certified. */
    int (*coeffs_err)(const double o[3], const double eo[3], const double d[3], const double ed[3],
                      const double *params, double *c, double *e);
} ig_shape;

/* All distinct roots of f(o + t d) in [tmin, tmax], ascending; returns the count (<= shape->degree).
 * Clips [tmin, tmax] to the shape's box first; computes the coefficients at a shifted origin o' = o + ts d
 * close to the object (the clipped interval's point closest to the box centre, or to the coordinate origin
 * for an unbounded shape), solves in the shifted parameter and shifts back, so a far-away ray loses nothing
 * to cancellation. roots[] needs room for IG_MAX_DEGREE entries. */
int ig_shape_roots(const ig_shape *shape, const double *params, const double o[3], const double d[3], double tmin,
                   double tmax, ig_root_method method, double *roots);

/* The nearest of those roots (what ig_shape_roots would list first) into *t: 1, or 0 when there is none.
 * The same clip and shift; the solver stops at the first root instead of isolating all (ig_first_root). */
int ig_shape_first_root(const ig_shape *shape, const double *params, const double o[3], const double d[3], double tmin,
                        double tmax, ig_root_method method, double *t);

/* ---- The same solve for a caller that solves one shape many times (the tracer) ----
 *
 * Everything ig_shape_roots works out from the shape and its params alone -- the box grown for the clip, the
 * finite axes and their centres -- done once by ig_shape_prepare. ig_shape_solve then gives, bit for bit, what
 * ig_shape_roots (first == 0) or ig_shape_first_root (first != 0) give for the same arguments; both are
 * written on top of it. The prep holds no pointers: it stays valid as long as shape and params are unchanged. */
typedef struct ig_shape_prep {
    int degree;             /* shape->degree; -1 when out of range or the shape has no coefficients (no roots) */
    int bounded;            /* shape->bounds returned 1 */
    int nclip, clip[3];     /* axes with a finite side, in ascending order: the only ones the clip can move */
    double lo[3], hi[3];    /* per axis, the box grown by 1e-9 of its finite extent (see shape.c) */
    int nfinite, finite[3]; /* axes with both sides finite, ascending: they place the shift point */
    double centre[3];       /* centre of each axis in finite[] (of the box as the spec gives it) */
} ig_shape_prep;

void ig_shape_prepare(const ig_shape *shape, const double *params, ig_shape_prep *prep);

/* The clip ig_shape_solve starts with: [*t0, *t1] narrowed to where o + t d is inside prep's box (grown, see
 * shape.c); 1 when that is not empty. For a caller that needs to know which rays reach the solve's work (the
 * floor report, bench/floor.py). */
int ig_shape_clip(const ig_shape_prep *prep, const double o[3], const double d[3], double *t0, double *t1);

/* The point ts of the ray o + t d, clamped to [t0, t1], that ig_shape_solve expands f(o + t d) around (shape.c
 * explains the rule); 0 when it is not finite. */
double ig_shape_shift_point(const ig_shape_prep *prep, const double o[3], const double d[3], double t0, double t1);

/* The expansion a solve worked on: roots are ts + s for the roots s of sum_k c[k] s^k (degree prep->degree).
 * A caller that needs the solver's own view of f near a root (the tracer's error bound of a hit point) reads
 * it here instead of computing the coefficients again. */
typedef struct ig_shape_expansion {
    double ts;
    double c[IG_MAX_DEGREE + 1];
} ig_shape_expansion;

/* shape, params and roots must not be NULL; prep must come from ig_shape_prepare(shape, params). ex may be
 * NULL; otherwise, when a root is returned, *ex holds the expansion it came from (else *ex is unspecified).
 * first: 0 all roots (ig_shape_roots), 1 the first (ig_shape_first_root), 2 a yes/no query -- at most one
 * value, where a root may sit, possibly unrefined (the tracer's opaque shadow rays; roots_impl.h's
 * IG_ANY_ROOT). */
int ig_shape_solve(const ig_shape *shape, const double *params, const ig_shape_prep *prep, const double o[3],
                   const double d[3], double tmin, double tmax, ig_root_method method, int first, double *roots,
                   ig_shape_expansion *ex);

/* Unit outward normal at p. At a singular point (grad f = 0 or not finite, e.g. a cone's apex) writes
 * (0, 0, 0) and returns 0 -- never NaN; the caller picks a fallback (e.g. facing the ray). Returns 1 otherwise. */
int ig_shape_normal(const ig_shape *shape, const double *params, const double p[3], double n[3]);

#endif
