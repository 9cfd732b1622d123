/* Small numerical kernels shared by the solvers, the shape layer and the tracer, defined once here as
 * static inline functions (they sit in hot loops; every caller gets its own inlined copy of the same
 * arithmetic).
 *
 * - error-free transformations: a + b and a * b as an unevaluated sum of two doubles, exactly;
 * - Horner's rule, plain and compensated (as accurate as Horner in twice the working precision);
 * - one axis of the slab test of a ray against an axis-aligned box;
 * - affine 3x4 maps (row-major, as tracer.h): a point, a vector, the inverse (the tracer and the Embree adapter
 *   move rays into object space with these, so both see the same object-space ray to the last bit).
 */
#ifndef IMPLGEN_NUMERICS_H
#define IMPLGEN_NUMERICS_H

#include <math.h>

/* s + e == a + b exactly, s = fl(a + b) (Knuth's TwoSum: no condition on the magnitudes). */
static inline void ig_two_sum(double a, double b, double *s, double *e)
{
    double x = a + b;
    double z = x - a;
    *e = (a - (x - z)) + (b - z);
    *s = x;
}

/* p + e == a * b exactly, p = fl(a * b): Dekker's product without FMA (the library is built for baseline
 * x86-64, where fma() is a slow call). Exact unless a * b underflows or a, b are beyond 2^996. */
static inline void ig_two_prod(double a, double b, double *p, double *e)
{
    const double split = 134217729.0; /* 2^27 + 1 */
    double x = a * b;
    double fa = split * a, fb = split * b;
    double ah = fa - (fa - a), al = a - ah;
    double bh = fb - (fb - b), bl = b - bh;
    *e = al * bl - (((x - ah * bh) - al * bh) - ah * bl);
    *p = x;
}

/* The larger of a and b, ignoring a NaN in b (fmax is a library call unless math errors are off). */
static inline double ig_max(double a, double b) { return b > a ? b : a; }

/* c[0] + c[1] x + ... + c[n] x^n by Horner's rule. */
static inline double ig_horner(const double *c, int n, double x)
{
    double v = c[n];
    for (int k = n - 1; k >= 0; --k)
        v = v * x + c[k];
    return v;
}

/* sum |c_k| x^k for x >= 0, by Horner's rule on the absolute values: the scale against which the rounding
 * error of evaluating the polynomial at +-x is bounded. */
static inline double ig_horner_abs(const double *c, int n, double x)
{
    double v = fabs(c[n]);
    for (int k = n - 1; k >= 0; --k)
        v = v * x + fabs(c[k]);
    return v;
}

/* The same by compensated Horner (Graillat, Langlois, Louvet 2005): the rounding error of every step is
 * carried along exactly and added back at the end, so the result is as accurate as Horner's rule in twice
 * the working precision. */
static inline double ig_horner_compensated(const double *c, int n, double x)
{
    double r = c[n], err = 0.0;
    for (int k = n - 1; k >= 0; --k) {
        double pr, pe, se;
        ig_two_prod(r, x, &pr, &pe);
        ig_two_sum(pr, c[k], &r, &se);
        err = err * x + (pe + se);
    }
    return r + err;
}

/* One axis of the slab test: the ray coordinate o + t d (d != 0, inv = 1 / d) lies between the planes lo and
 * hi for t in [*ta, *tb] (ordered). Returns 1 when ordering swapped the two (d < 0: the ray enters through
 * hi), else 0. A NaN plane gives a NaN end and no swap. Every ray/box clip of the runtime (shape.c,
 * tracer_hit.c) is built on this, so they all compute the same distances to the last bit. */
static inline int ig_slab(double lo, double hi, double o, double inv, double *ta, double *tb)
{
    double a = (lo - o) * inv, b = (hi - o) * inv;
    if (a > b) {
        *ta = b;
        *tb = a;
        return 1;
    }
    *ta = a;
    *tb = b;
    return 0;
}

/* out = M p + translation (out may alias p). */
static inline void ig_affine_point(const double m[12], const double p[3], double out[3])
{
    double r[3];
    int i;
    for (i = 0; i < 3; ++i)
        r[i] = m[4 * i] * p[0] + m[4 * i + 1] * p[1] + m[4 * i + 2] * p[2] + m[4 * i + 3];
    out[0] = r[0];
    out[1] = r[1];
    out[2] = r[2];
}

/* out = M v, the linear part only (out may alias v). */
static inline void ig_affine_vector(const double m[12], const double v[3], double out[3])
{
    double r[3];
    int i;
    for (i = 0; i < 3; ++i)
        r[i] = m[4 * i] * v[0] + m[4 * i + 1] * v[1] + m[4 * i + 2] * v[2];
    out[0] = r[0];
    out[1] = r[1];
    out[2] = r[2];
}

/* inv = M^-1 by cofactors. Returns 0 (inv untouched) when M's linear part is zero, not finite, or singular to
 * within 1e-12 of its scale cubed. */
static inline int ig_affine_invert(const double m[12], double inv[12])
{
    double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], k = m[10];
    double c00 = e * k - f * h, c01 = c * h - b * k, c02 = b * f - c * e;
    double c10 = f * g - d * k, c11 = a * k - c * g, c12 = c * d - a * f;
    double c20 = d * h - e * g, c21 = b * g - a * h, c22 = a * e - b * d;
    double det = a * c00 + b * c10 + c * c20;
    double scale = 0.0, t[3];
    int i;
    for (i = 0; i < 12; ++i)
        if (i % 4 != 3 && fabs(m[i]) > scale)
            scale = fabs(m[i]);
    if (!(scale > 0.0) || !isfinite(det) || fabs(det) <= 1e-12 * scale * scale * scale)
        return 0;
    inv[0] = c00 / det;
    inv[1] = c01 / det;
    inv[2] = c02 / det;
    inv[4] = c10 / det;
    inv[5] = c11 / det;
    inv[6] = c12 / det;
    inv[8] = c20 / det;
    inv[9] = c21 / det;
    inv[10] = c22 / det;
    inv[3] = inv[7] = inv[11] = 0.0;
    t[0] = m[3];
    t[1] = m[7];
    t[2] = m[11];
    ig_affine_vector(inv, t, t);
    inv[3] = -t[0];
    inv[7] = -t[1];
    inv[11] = -t[2];
    return 1;
}

#endif
