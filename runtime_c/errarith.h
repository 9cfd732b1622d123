/* Running error analysis for the generated `<name>_coeffs_err` functions (implgen.codegen.backends.c.errbound):
 * each helper takes the two operands' computed values a, b with bounds ea, eb on their distance from the exact
 * values, and the computed result v = fl(a op b), and returns a bound on v's distance from the exact result.
 *
 * Round to nearest: |fl(x) - x| <= U |x|, plus ETA for a product or quotient in the subnormal range. The bound
 * is itself computed in floating point with at most six roundings, each relative U, so it is multiplied by
 * G = 1 + 2^-50 (G_DIV = 1 + 2^-48 for the quotient's longer chain), which covers them. A NaN or infinite
 * result gives an infinite or NaN bound: the caller refuses it (docs/certify.md). */
#ifndef IMPLGEN_ERRARITH_H
#define IMPLGEN_ERRARITH_H

#include <math.h>

#define IG_ERR_U 1.1102230246251565e-16    /* 2^-53 */
#define IG_ERR_ETA 4.9406564584124654e-324 /* 2^-1074 */
#define IG_ERR_G 1.0000000000000009        /* 1 + 2^-50 */
#define IG_ERR_G_DIV 1.0000000000000036    /* 1 + 2^-48 */

/* A constant rounded once from an exact rational. */
static inline double ig_err_const(double v) { return IG_ERR_U * fabs(v) * IG_ERR_G; }

/* a + b or a - b: the operands' bounds add, plus the rounding of the result (exact below DBL_MIN). */
static inline double ig_err_add(double a, double ea, double b, double eb, double v)
{
    (void)a;
    (void)b;
    return (ea + eb + IG_ERR_U * fabs(v)) * IG_ERR_G;
}

/* a * b: |A B - a b| <= |a| eb + |b| ea + ea eb for |A - a| <= ea, |B - b| <= eb. */
static inline double ig_err_mul(double a, double ea, double b, double eb, double v)
{
    return (fabs(a) * eb + fabs(b) * ea + ea * eb + IG_ERR_U * fabs(v) + IG_ERR_ETA) * IG_ERR_G;
}

/* a / b: |A / B - a / b| <= (|a| eb + |b| ea) / (|b| (|b| - eb)) when |b| > eb; infinite otherwise. */
static inline double ig_err_div(double a, double ea, double b, double eb, double v)
{
    double m = fabs(b) - eb;
    if (!(m > 0.0))
        return INFINITY;
    return ((fabs(a) * eb + fabs(b) * ea) / (fabs(b) * m) + IG_ERR_U * fabs(v) + IG_ERR_ETA) * IG_ERR_G_DIV;
}

#endif
