/* TEST FIXTURE ONLY: a plain ig_shape_roots / ig_shape_normal used by the tracer's C tests while
 * runtime_c/shape.c (issue 3) is not in the tree. The tests link runtime_c/shape.c instead whenever it
 * exists. Box clip, origin shift to the clipped interval's point nearest the box centre (or the coordinate
 * origin), ig_real_roots, shift back. */
#include "shape.h"

#include <math.h>

static int clip(const double box[6], const double o[3], const double d[3], double *lo, double *hi)
{
    int a;
    for (a = 0; a < 3; ++a) {
        if (d[a] == 0.0) {
            if (o[a] < box[a] || o[a] > box[a + 3]) return 0;
        } else {
            double t0 = (box[a] - o[a]) / d[a], t1 = (box[a + 3] - o[a]) / d[a];
            if (t0 > t1) { double t = t0; t0 = t1; t1 = t; }
            if (t0 > *lo) *lo = t0;
            if (t1 < *hi) *hi = t1;
        }
    }
    return *lo <= *hi;
}

int ig_shape_roots(const ig_shape *shape, const double *params, const double o[3], const double d[3],
                   double tmin, double tmax, ig_root_method method, double *roots)
{
    double box[6], c[IG_MAX_DEGREE + 1], centre[3] = {0.0, 0.0, 0.0}, os[3], ts, dd;
    int a, n, i;
    if (shape->bounds(params, box)) {
        if (!clip(box, o, d, &tmin, &tmax)) return 0;
        for (a = 0; a < 3; ++a)
            centre[a] = (isfinite(box[a]) && isfinite(box[a + 3])) ? 0.5 * (box[a] + box[a + 3]) : 0.0;
    }
    dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if (!(dd > 0.0)) return 0;
    ts = ((centre[0] - o[0]) * d[0] + (centre[1] - o[1]) * d[1] + (centre[2] - o[2]) * d[2]) / dd;
    if (ts < tmin) ts = tmin;
    if (ts > tmax) ts = tmax;
    if (!isfinite(ts)) ts = 0.0;
    for (a = 0; a < 3; ++a) os[a] = o[a] + ts * d[a];
    shape->coeffs(os, d, params, c);
    n = ig_real_roots(c, shape->degree, tmin - ts, tmax - ts, method, roots);
    for (i = 0; i < n; ++i) roots[i] += ts;
    return n;
}

int ig_shape_normal(const ig_shape *shape, const double *params, const double p[3], double n[3])
{
    double g[3], l;
    shape->gradient(p, params, g);
    l = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    if (!(l > 0.0) || !isfinite(l)) { n[0] = n[1] = n[2] = 0.0; return 0; }
    n[0] = g[0] / l; n[1] = g[1] / l; n[2] = g[2] / l;
    return 1;
}
