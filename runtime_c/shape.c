/* Ray/shape intersection with the origin shift, and the never-NaN normal. See shape.h for the contract.
 *
 * Why the shift: the coefficients of f(o + t d) are sums of terms as large as |o|^deg that cancel down to
 * the size of f near the object; seen from 1e4 units a unit torus loses ~16 digits and half of its hit/miss
 * decisions. Expanding at o' = o + ts d, a point of the ray next to the object, keeps every term at the
 * object's own scale; the root s of f(o' + s d) then gives t = ts + s, and t is only rounded once.
 *
 * The shift point ts: the point of the clipped interval [t0, t1] closest (in the finite axes of the box) to
 * the box centre; with no finite axis -- an unbounded shape -- closest to the coordinate origin. An axis is
 * finite when both its bounds are; a half-open axis has no centre and is left out. The same rule is
 * implemented in NumPy by implgen.raycast for the generated Python modules.
 */
#include "shape.h"
#include "numerics.h"
#include "roots_impl.h"

#include <math.h>
#include <stddef.h>

void ig_shape_prepare(const ig_shape *shape, const double *params, ig_shape_prep *prep)
{
    double box[6] = {-INFINITY, -INFINITY, -INFINITY, INFINITY, INFINITY, INFINITY};
    prep->degree =
        (shape && shape->coeffs && shape->degree >= 0 && shape->degree <= IG_MAX_DEGREE) ? shape->degree : -1;
    prep->bounded = (shape && shape->bounds) ? shape->bounds(params, box) : 0;
    prep->nclip = prep->nfinite = 0;
    for (int i = 0; i < 3; ++i) {
        /* the box grows by 1e-9 of its finite extent: a surface that touches its own box (the torus at
         * |x| = a + b) keeps the root there despite the rounding of the slab distances */
        double lo = box[i], hi = box[i + 3], scale = 0.0;
        if (isfinite(lo))
            scale = fabs(lo);
        if (isfinite(hi) && fabs(hi) > scale)
            scale = fabs(hi);
        prep->lo[i] = lo - 1e-9 * scale;
        prep->hi[i] = hi + 1e-9 * scale;
        prep->centre[i] = 0.0;
        if (!prep->bounded)
            continue;
        /* an axis open on both sides (-inf or NaN below, +inf or NaN above) can neither move nor empty the
         * interval: the clip skips it */
        if (!((lo == -INFINITY || isnan(lo)) && (hi == INFINITY || isnan(hi))))
            prep->clip[prep->nclip++] = i;
        if (isfinite(lo) && isfinite(hi)) {
            prep->finite[prep->nfinite++] = i;
            prep->centre[i] = 0.5 * lo + 0.5 * hi;
        }
    }
}

/* Slab clip of [*t0, *t1] against the grown box; an infinite bound imposes nothing on its side. 0 when empty.
 * Unlike the tracer's rt_clip_box it neither tests the box for emptiness nor stops early: prepare() built the
 * box, and only its clipping axes are visited. */
static int clip_box(const ig_shape_prep *prep, const double o[3], const double d[3], double *t0, double *t1)
{
    for (int k = 0; k < prep->nclip; ++k) {
        int i = prep->clip[k];
        double lo = prep->lo[i], hi = prep->hi[i];
        if (d[i] == 0.0) {
            if (o[i] < lo || o[i] > hi)
                return 0;
            continue;
        }
        double ta, tb;
        ig_slab(lo, hi, o[i], 1.0 / d[i], &ta, &tb);
        if (ta > *t0)
            *t0 = ta;
        if (tb < *t1)
            *t1 = tb;
    }
    return *t0 <= *t1;
}

int ig_shape_clip(const ig_shape_prep *prep, const double o[3], const double d[3], double *t0, double *t1)
{
    return prep->bounded ? clip_box(prep, o, d, t0, t1) : *t0 <= *t1;
}

/* The shift point: minimises sum over finite axes of (o_i + t d_i - c_i)^2, clamped to [t0, t1]. Inline here, so
 * that every solve has it without a call; ig_shape_shift_point is the same for other callers. */
static inline double shift_point(const ig_shape_prep *prep, const double o[3], const double d[3], double t0, double t1)
{
    double num = 0.0, den = 0.0;
    for (int k = 0; k < prep->nfinite; ++k) {
        int i = prep->finite[k];
        num += d[i] * (prep->centre[i] - o[i]);
        den += d[i] * d[i];
    }
    if (!(den > 0.0)) { /* unbounded, or the ray runs parallel to every finite axis: coordinate origin */
        num = -(o[0] * d[0] + o[1] * d[1] + o[2] * d[2]);
        den = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    }
    double ts = num / den;
    if (!isfinite(ts))
        ts = 0.0;
    if (ts < t0)
        ts = t0;
    if (ts > t1)
        ts = t1;
    return ts;
}

double ig_shape_shift_point(const ig_shape_prep *prep, const double o[3], const double d[3], double t0, double t1)
{
    return shift_point(prep, o, d, t0, t1);
}

int ig_shape_solve(const ig_shape *shape, const double *params, const ig_shape_prep *prep, const double o[3],
                   const double d[3], double tmin, double tmax, ig_root_method method, int first, double *roots,
                   ig_shape_expansion *ex)
{
    int finite = 1; /* one branch for the six: isfinite(x) is |x| <= DBL_MAX (false for NaN) */
    for (int i = 0; i < 3; ++i)
        finite &= (fabs(o[i]) <= DBL_MAX) & (fabs(d[i]) <= DBL_MAX);
    if (!finite)
        return 0;
    if (d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0)
        return 0;
    if (!(tmin <= tmax))
        return 0;
    int n = prep->degree;
    if (n < 0)
        return 0;
    double t0 = tmin, t1 = tmax;
    if (prep->bounded && !clip_box(prep, o, d, &t0, &t1))
        return 0;
    double ts = shift_point(prep, o, d, t0, t1);
    if (!isfinite(ts)) /* clamped to an infinite end */
        ts = 0.0;
    double os[3] = {o[0] + ts * d[0], o[1] + ts * d[1], o[2] + ts * d[2]};
    double c[IG_MAX_DEGREE + 1];
    shape->coeffs(os, d, params, c);
    double s[IG_MAX_DEGREE];
    int k = n <= 2 ? ig_roots_low(c, n, t0 - ts, t1 - ts, first, s)
                   : ig_roots_core(c, n, t0 - ts, t1 - ts, (int)method, first, s);
    int m = 0;
    for (int i = 0; i < k; ++i) {
        double t = ts + s[i];
        if (t < t0) /* rounding of the shift back must not leave [t0, t1] */
            t = t0;
        if (t > t1)
            t = t1;
        if (m == 0 || t > roots[m - 1])
            roots[m++] = t;
    }
    if (ex && m > 0) {
        ex->ts = ts;
        for (int i = 0; i <= n; ++i)
            ex->c[i] = c[i];
    }
    return m;
}

/* Clip, shift, coefficients, solve (all roots, or only the first), shift back. */
static int shape_solve(const ig_shape *shape, const double *params, const double o[3], const double d[3], double tmin,
                       double tmax, ig_root_method method, int first, double *roots)
{
    ig_shape_prep prep;
    if (!shape || !shape->coeffs || !roots)
        return 0;
    ig_shape_prepare(shape, params, &prep);
    return ig_shape_solve(shape, params, &prep, o, d, tmin, tmax, method, first, roots, NULL);
}

int ig_shape_roots(const ig_shape *shape, const double *params, const double o[3], const double d[3], double tmin,
                   double tmax, ig_root_method method, double *roots)
{
    return shape_solve(shape, params, o, d, tmin, tmax, method, 0, roots);
}

int ig_shape_first_root(const ig_shape *shape, const double *params, const double o[3], const double d[3], double tmin,
                        double tmax, ig_root_method method, double *t)
{
    return shape_solve(shape, params, o, d, tmin, tmax, method, 1, t);
}

int ig_shape_normal(const ig_shape *shape, const double *params, const double p[3], double n[3])
{
    n[0] = n[1] = n[2] = 0.0;
    if (!shape || !shape->gradient)
        return 0;
    double g[3];
    shape->gradient(p, params, g);
    double m = 0.0;
    for (int i = 0; i < 3; ++i) {
        if (!isfinite(g[i]))
            return 0;
        if (fabs(g[i]) > m)
            m = fabs(g[i]);
    }
    if (m == 0.0)
        return 0;
    /* scale by the largest component first: no overflow or underflow in the squares */
    double x = g[0] / m, y = g[1] / m, z = g[2] / m;
    double len = sqrt(x * x + y * y + z * z);
    n[0] = x / len;
    n[1] = y / len;
    n[2] = z / len;
    return 1;
}
