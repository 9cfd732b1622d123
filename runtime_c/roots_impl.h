/* Internals shared by the root solvers (roots*.c: the dispatcher, the methods, roots_common.c, roots_refine.c
 * and roots_bench.c).
 * Not part of the public contract: only roots.h is. Every symbol carries the ig_ prefix because all
 * runtime .c files are compiled into one library.
 */
#ifndef IMPLGEN_ROOTS_IMPL_H
#define IMPLGEN_ROOTS_IMPL_H

#include "numerics.h"
#include "roots.h"

/* Room for intermediate root lists (a method returns at most n + 1 candidates per piece, three pieces). */
#define IG_ROOT_BUF (3 * (IG_MAX_DEGREE + 2))

/* Unit roundoff of IEEE double, 2^-53. */
#define IG_U 1.1102230246251565e-16

/* Bench-only method ids (beyond ig_root_method): the classic closed forms without any polishing,
 * i.e. what Schwarze's Graphics Gems code does. Used by `implgen bench solvers` as the baseline. */
#define IG_ROOTS_CLOSED_PLAIN 10

/* Horner evaluation of c[0..n] at x: value and derivative (roots_common.c). */
void ig_horner2(const double *c, int n, double x, double *p, double *dp);

/* Sign of p(x) that rounding cannot flip: -1 or +1, or 0 when |p(x)| is within the rounding error even of
 * a compensated (twice-the-working-precision) evaluation -- then x is taken as a root. *val gets p(x). */
int ig_sign_certified(const double *c, int n, double x, double *val);

/* The root of c on a bracket [l, r] where c changes sign (vl, vr: the values there, nonzero): Householder's
 * third-order step (order-four convergence) with bisection, then, for anything unusual, a safeguarded Newton
 * that bisects in the ordering of doubles (at most 64 halvings span the whole range). Never leaves the
 * bracket; a bounded number of iterations. tol: relative accuracy wanted (2^-52: full); x0: a starting guess
 * (NaN or outside the bracket: false position). */
double ig_refine(const double *c, int n, double l, double r, double vl, double vr, double tol, double x0);

/* ig_refine on k brackets of the same polynomial at once (four evaluation chains in flight): roots[i] is
 * bitwise what ig_refine(c, n, l[i], r[i], vl[i], vr[i], tol, x0[i]) returns. */
void ig_refine_many(const double *c, int n, int k, const double *l, const double *r, const double *vl, const double *vr,
                    double tol, const double *x0, double *roots);

/* Midpoint of [l, r] in the ordering of doubles (halves the number of doubles between them). */
double ig_ordered_mid(double l, double r);

/* Real roots of c0 + c1 x + c2 x^2 (c2 != 0), distinct, ascending; a double root once. */
int ig_quadratic(double c0, double c1, double c2, double *r);

/* Sort ascending (insertion sort: the lists are short). */
void ig_sort(double *r, int k);

/* Sort ascending and drop exact duplicates; returns the new count. */
int ig_sort_unique(double *r, int k);

/* ig_roots_core for a nominal degree n <= 2 (a plane's or a quadric's ray polynomial), the method aside (every
 * method solves these in closed form): the same pipeline -- bad input, exact rescaling, the degree dropped while the
 * leading coefficient is zero, zero roots taken out, the closed form, then sorting and keeping the roots in
 * [lo, hi] -- written inline, so that the shape layer's many low-degree solves (every CSG leaf of a glass) skip the
 * general entry. roots.c's ig_roots_stats answers n <= 2 with it too: one implementation. */
static inline int ig_roots_low(const double *c, int n, double lo, double hi, int first, double *roots)
{
    double p[3], r[3], cmax = 0.0;
    int k, top, m, deg, cnt = 0, most = first ? 1 : n;
    if (!(lo <= hi)) /* also NaN bounds */
        return 0;
    if (n == 1) { /* a plane, the common case in a scene: no set-up, no scaling needed (the quotient is
                   * scale-free); c[0] == 0 gives +0, c[1] == 0 no root */
        double x = -c[0] / c[1];
        if (!(fabs(c[0]) <= DBL_MAX) || !(fabs(c[1]) <= DBL_MAX) || !isfinite(x) || !(x >= lo && x <= hi))
            return 0; /* also c[1] == 0: no root, or the zero polynomial */
        roots[0] = x == 0.0 ? 0.0 : x;
        return 1;
    }
    for (k = 0; k <= n; ++k) {
        double a = fabs(c[k]);
        if (!(a <= DBL_MAX)) /* NaN or Inf */
            return 0;
        cmax = a > cmax ? a : cmax;
    }
    if (cmax == 0.0)
        return 0;                            /* the zero polynomial: every t is a root; reported as none */
    if (cmax > 0x1p200 || cmax < 0x1p-200) { /* exact rescaling by a power of two */
        int e = ilogb(cmax);
        double s1 = ldexp(1.0, -e / 2), s2 = ldexp(1.0, -e - (-e / 2));
        for (k = 0; k <= n; ++k)
            p[k] = (c[k] * s1) * s2;
    } else {
        for (k = 0; k <= n; ++k)
            p[k] = c[k];
    }
    top = n;
    while (top > 0 && p[top] == 0.0)
        --top;
    m = 0; /* multiplicity of the root t = 0 */
    while (m < top && p[m] == 0.0)
        ++m;
    deg = top - m;
    k = 0;
    if (deg == 1) {
        double x = -p[m] / p[m + 1];
        if (isfinite(x))
            r[k++] = x;
    } else if (deg == 2) {
        k = ig_quadratic(p[0], p[1], p[2], r);
    }
    if (m > 0)
        r[k++] = 0.0;
    if (k > 1 && (deg != 2 || m > 0)) /* ig_quadratic lists its roots ascending and distinct already */
        k = ig_sort_unique(r, k);
    for (m = 0; m < k && cnt < most; ++m)
        if (r[m] >= lo && r[m] <= hi && isfinite(r[m]))
            roots[cnt++] = r[m] == 0.0 ? 0.0 : r[m]; /* no -0 */
    return cnt;
}

/* Closed forms on a polynomial of exact degree 3 or 4 (c[n] != 0, c[0] != 0, coefficients scaled to max 1):
 * all real roots in [lo, hi], ascending. polish != 0: Newton-polished, factorisation refined; 0: classic. */
int ig_closed_cubic(const double *c, double lo, double hi, int polish, double *r);
int ig_closed_quartic(const double *c, double lo, double hi, int polish, double *r);

/* Derivative bracketing on a finite [a, b] for exact degree n >= 3 (c[n] != 0, c[0] != 0). */
int ig_bracket_interval(const double *c, int n, double a, double b, double *r);

/* Its first root only (at most one, into r[0]): bitwise the first of ig_bracket_interval's list, with the
 * derivative levels run lazily left to right. */
int ig_bracket_first(const double *c, int n, double a, double b, double *r);

/* ig_bracket_first when first != 0, else ig_bracket_interval. */
int ig_bracket_roots(const double *c, int n, double a, double b, int first, double *r);

/* Bernstein subdivision on a finite [a, b], same preconditions; hands a piece it cannot decide to
 * ig_bracket_interval (and counts it in *fallbacks unless that is NULL). _first: the leftmost root only. */
int ig_bernstein_interval(const double *c, int n, double a, double b, int *fallbacks, double *r);
int ig_bernstein_first(const double *c, int n, double a, double b, int *fallbacks, double *r);
/* IG_ANY_ROOT: a point where a root sits, unrefined when certified (see below). */
int ig_bernstein_any(const double *c, int n, double a, double b, int *fallbacks, double *r);

/* Sturm isolation on a finite interval [a, b] for exact degree n >= 3 (c[n] != 0, c[0] != 0). */
int ig_sturm_interval(const double *c, int n, double a, double b, double *r);

/* The real-roots entry point with a bench-only method id allowed (see IG_ROOTS_CLOSED_PLAIN). */
int ig_real_roots_any(const double *c, int n, double lo, double hi, int method, double *roots);

/* The modes of the `first` argument below. IG_ANY_ROOT is a yes/no query (the tracer's opaque shadow rays):
 * at most one value, a point of [lo, hi] where some root may sit -- the first root refined, or, from the Bernstein
 * method, a point strictly inside an interval that holds a root, left unrefined: a piece certified to hold exactly
 * one simple root (sign change at both ends, one sign variation), or two points of [lo, hi] where p's certified
 * signs differ (an odd number of roots between them; the first such pair the subdivision meets, its middle).
 * Methods without such pieces answer as IG_FIRST_ROOT. */
enum { IG_ALL_ROOTS = 0, IG_FIRST_ROOT = 1, IG_ANY_ROOT = 2 };

/* The same with first != 0: only the smallest root (at most one), as ig_first_root. */
int ig_roots_core(const double *c, int n, double lo, double hi, int method, int first, double *roots);

/* ig_roots_core that also counts, into *fallbacks (NULL: not counted), the Bernstein pieces handed to
 * bracketing: the solver report's statistics. */
int ig_roots_stats(const double *c, int n, double lo, double hi, int method, int first, int *fallbacks, double *roots);

/* Batch form of ig_first_root for the Python binding: root i (or NaN) to roots[i], 0/1 to counts[i]. */
void ig_first_root_batch(const double *c, int n, long count, const double *lo, const double *hi, int method,
                         double *roots, int *counts);

/* Batch form for the Python binding: `count` polynomials of nominal degree n, coefficients at c + i*(n+1),
 * bounds lo[i], hi[i]; roots of polynomial i go to roots + i*n (padded with NaN), its count to counts[i]. */
void ig_real_roots_batch(const double *c, int n, long count, const double *lo, const double *hi, int method,
                         double *roots, int *counts);

/* Timing entry point for the solver report: solves each polynomial once, measures its time with
 * clock_gettime(CLOCK_MONOTONIC) minus the calibrated cost of the clock reads, and writes ns per solve to
 * ns[i]; roots/counts as in ig_real_roots_batch. Returns the total wall time of an untimed second pass
 * over all polynomials in ns (throughput measure). */
double ig_bench_solve_batch(const double *c, int n, long count, const double *lo, const double *hi, int method,
                            double *roots, int *counts, double *ns);

#endif
