/* Batch forms of ig_shape_roots and of the shape's value and gradient. See shape_batch.h. */
#include "shape_batch.h"
#include <math.h>

#include <stddef.h>

void ig_shape_roots_many(const ig_shape *shape, const double *params, long n, const double *o, const double *d,
                         const double *tmin, const double *tmax, ig_root_method method, double *roots, int *counts)
{
    ig_shape_prep prep;
    if (!shape || !o || !d || !tmin || !tmax || !roots || !counts)
        return;
    ig_shape_prepare(shape, params, &prep);
    for (long i = 0; i < n; ++i) {
        double *r = roots + (size_t)i * IG_MAX_DEGREE;
        counts[i] = shape->coeffs ? ig_shape_solve(shape, params, &prep, o + 3 * (size_t)i, d + 3 * (size_t)i, tmin[i],
                                                   tmax[i], method, 0, r, NULL)
                                  : 0;
    }
}

void ig_shape_eval_many(const ig_shape *shape, const double *params, long n, const double *p, double *f, double *g)
{
    if (!shape || !p || !f)
        return;
    for (long i = 0; i < n; ++i) { /* a shape without value or gradient gives NaN, never leaves them unwritten */
        f[i] = shape->value ? shape->value(p + 3 * (size_t)i, params) : NAN;
        if (g && shape->gradient)
            shape->gradient(p + 3 * (size_t)i, params, g + 3 * (size_t)i);
        else if (g)
            g[3 * (size_t)i] = g[3 * (size_t)i + 1] = g[3 * (size_t)i + 2] = NAN;
    }
}

void ig_shape_values_grid(const ig_shape *shape, const double *params, const double *x, long nx, const double *y,
                          long ny, const double *z, long nz, double *f)
{
    if (!shape || !shape->value || !x || !y || !z || !f)
        return;
    for (long i = 0; i < nx; ++i)
        for (long j = 0; j < ny; ++j)
            for (long k = 0; k < nz; ++k) {
                double p[3] = {x[i], y[j], z[k]};
                f[((size_t)i * (size_t)ny + (size_t)j) * (size_t)nz + (size_t)k] = shape->value(p, params);
            }
}

/* One point's Newton steps of least norm onto f = 0; 1 when it converged (see shape_batch.h). */
static int project_one(const ig_shape *shape, const double *params, double *p, int steps, double tol, double noise)
{
    double prev = INFINITY, size = INFINITY;
    for (int k = 0; k < steps; ++k) {
        double g[3], s[3];
        double f = shape->value(p, params);
        shape->gradient(p, params, g);
        double gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
        if (!(gg > 0)) /* no direction to step in */
            return 0;
        double c = -(f / gg);
        for (int i = 0; i < 3; ++i)
            s[i] = c * g[i];
        if (!isfinite(s[0]) || !isfinite(s[1]) || !isfinite(s[2]))
            return 0;
        for (int i = 0; i < 3; ++i)
            p[i] += s[i];
        size = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        if (size <= tol || (size > 0.5 * prev && size <= noise))
            return 1;
        prev = size;
    }
    return size <= noise;
}

void ig_shape_project_many(const ig_shape *shape, const double *params, long n, double *p, int steps, double tol,
                           double noise, double reach, unsigned char *ok)
{
    if (!shape || !p || !ok)
        return;
    for (long i = 0; i < n; ++i) {
        double *q = p + 3 * (size_t)i, start[3] = {q[0], q[1], q[2]};
        int done = shape->value && shape->gradient && project_one(shape, params, q, steps, tol, noise);
        for (int k = 0; k < 3; ++k) /* NaN fails this test too */
            done = done && fabs(q[k] - start[k]) <= reach;
        ok[i] = (unsigned char)done;
    }
}
