/* Small numerical kernels shared by the solvers, the shape layer and the tracer, defined once here as
 * static inline functions (they sit in hot loops; every caller gets its own inlined copy of the same
 * arithmetic).
 *
 * - error-free transformations: a + b and a * b as an unevaluated sum of two doubles, exactly;
 * - Horner's rule, plain and compensated (as accurate as Horner in twice the working precision);
 * - one axis of the slab test of a ray against an axis-aligned box.
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

#endif
