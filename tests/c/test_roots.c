/* Standalone checks of ig_real_roots and ig_first_root on built hard cases, every method, as named cases
 * (tests/c/ctest.h); run by tests/test_c_drivers_roots.py under AddressSanitizer + UBSan, each case reported
 * by name. The expected roots are known exactly (products of known factors, mostly dyadic so the double
 * coefficients are exact). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ctest.h"
#include "poly_from_roots.h"
#include "roots.h"
#include "roots_impl.h"

/* method masks: bit m for ig_root_method m */
#define NMETHODS 5
#define ALL 31
#define NO_CLOSED (31 & ~2)
#define NO_STURM (31 & ~4)
#define GENERAL (1 | 8 | 16) /* auto, bracket and bernstein */

static const char *method_names[NMETHODS] = {"auto", "closed", "sturm", "bracket", "bernstein"};

/* ig_first_root against the expected smallest root (within rtol, inside [lo, hi]) and against what
 * ig_real_roots listed first (k roots in r): a root exactly when that list is not empty, and bitwise the same
 * double for every method (Bernstein visits its pieces left to right in both modes and hands a piece it cannot
 * decide to bracketing alone, so both modes compute the first root the same way). It writes one double at most. */
#define BITWISE_FIRST ALL

static void check_first(ctest *t, const char *name, const double *c, int n, double lo, double hi, const double *want,
                        int nw, double rtol, int m, int k, const double *r)
{
    double f[4] = {-12345.0, -12345.0, -12345.0, -12345.0};
    int got = ig_first_root(c, n, lo, hi, (ig_root_method)m, f);
    int ok = got == (nw > 0) && f[1] == -12345.0 && f[2] == -12345.0 && f[3] == -12345.0;
    if (ok && got) {
        if (!(fabs(f[0] - want[0]) <= rtol * fmax(fabs(want[0]), 1e-300)) || f[0] < lo || f[0] > hi)
            ok = 0;
        if (((1 << m) & BITWISE_FIRST) && k > 0 && memcmp(&f[0], &r[0], sizeof f[0]) != 0)
            ok = 0;
    }
    if (ok && got != (k > 0))
        ok = 0;
    if (!ok) {
        ctest_fail(t,
                   "first root of %s [%s]: got %d (%.17g, writes beyond: %d), want %d (%.17g); "
                   "ig_real_roots listed %d first %.17g",
                   name, method_names[m], got, f[0], f[1] != -12345.0 || f[2] != -12345.0 || f[3] != -12345.0, nw > 0,
                   nw > 0 ? want[0] : NAN, k, k > 0 ? r[0] : NAN);
    }
}

/* The yes/no query (IG_ANY_ROOT, the tracer's opaque shadow rays): a value exactly when a root lies in
 * [lo, hi], one double at most, inside [lo, hi] and -- a refined root, a point of a piece no longer than half the
 * interval that holds one, or the middle of an interval no longer than [lo, hi] whose ends have certified opposite
 * signs -- within half the interval of a wanted root. (A middle between two points of opposite sign may lie as far
 * from the roots on either side: no more is asked of it.) */
static void check_any(ctest *t, const char *name, const double *c, int n, double lo, double hi, const double *want,
                      int nw, int m)
{
    double f[4] = {-12345.0, -12345.0, -12345.0, -12345.0}, near = INFINITY;
    int got = ig_roots_core(c, n, lo, hi, m, IG_ANY_ROOT, f);
    int ok = got == (nw > 0) && f[1] == -12345.0 && f[2] == -12345.0 && f[3] == -12345.0;
    for (int i = 0; i < nw; ++i)
        near = fmin(near, fabs(f[0] - want[i]));
    if (ok && got && (f[0] < lo || f[0] > hi || (isfinite(hi - lo) && !(near <= 0.5 * (hi - lo) * (1 + 1e-15)))))
        ok = 0;
    if (!ok) {
        ctest_fail(t, "any root of %s [%s]: got %d (%.17g), want %d", name, method_names[m], got, f[0], nw > 0);
    }
}

static void expect(ctest *t, const char *name, const double *c, int n, double lo, double hi, const double *want, int nw,
                   double rtol, int methods)
{
    for (int m = 0; m < NMETHODS; ++m) {
        if (!(methods & (1 << m)))
            continue;
        double r[IG_MAX_DEGREE + 8];
        for (int i = 0; i < IG_MAX_DEGREE + 8; ++i)
            r[i] = -12345.0; /* canary: nothing beyond n may be written */
        int k = ig_real_roots(c, n, lo, hi, (ig_root_method)m, r);
        int ok = k == nw;
        for (int i = 0; ok && i < k; ++i) {
            if (!(fabs(r[i] - want[i]) <= rtol * fmax(fabs(want[i]), 1e-300)) || isnan(r[i]))
                ok = 0;
            if (i > 0 && !(r[i] > r[i - 1]))
                ok = 0;
            if (r[i] < lo || r[i] > hi)
                ok = 0;
        }
        for (int i = (n > 0 ? n : 0); i < IG_MAX_DEGREE + 8; ++i)
            if (r[i] != -12345.0)
                ok = 0;
        if (!ok) {
            char got[30 * 26] = "", wanted[IG_MAX_DEGREE * 26] = "";
            for (int i = 0, at = 0; i < k && i < 30; ++i)
                at += snprintf(got + at, sizeof got - (size_t)at, " %.17g", r[i]);
            for (int i = 0, at = 0; i < nw && i < IG_MAX_DEGREE; ++i)
                at += snprintf(wanted + at, sizeof wanted - (size_t)at, " %.17g", want[i]);
            ctest_fail(t, "%s [%s]: got %d roots:%s; want %d:%s", name, method_names[m], k, got, nw, wanted);
        }
        check_first(t, name, c, n, lo, hi, want, nw, rtol, m, k, r);
        check_any(t, name, c, n, lo, hi, want, nw, m);
    }
}

/* four simple roots */
static void four_simple_roots(ctest *t)
{
    double c[IG_MAX_DEGREE + 3];
    const double inf = INFINITY;
    int n;
    double r[] = {1, 2, 3, 4};
    n = from_roots(r, 4, NULL, 0, 1.0, c);
    expect(t, "simple 1..4", c, n, -inf, inf, r, 4, 1e-14, ALL);
    double w[] = {2, 3};
    expect(t, "roots exactly at lo and hi", c, n, 2.0, 3.0, w, 2, 0.0, ALL);
    double w4[] = {4};
    expect(t, "root exactly at lo only", c, n, 4.0, 10.0, w4, 1, 0.0, ALL);
    expect(t, "lo == hi at a root", c, n, 3.0, 3.0, r + 2, 1, 0.0, ALL);
    expect(t, "interval without roots", c, n, 4.5, 9.0, NULL, 0, 0.0, ALL);
}

/* degree drop: vanishing leading coefficients, nominal degree 4 */
static void degree_drops_when_leading_coefficients_vanish(ctest *t)
{
    const double inf = INFINITY;
    double c1[] = {-2, 1, 0, 0, 0}, w1[] = {2};
    expect(t, "degree drop to 1", c1, 4, -inf, inf, w1, 1, 0.0, ALL);
    double c2[] = {6, -5, 1, 0, 0}, w2[] = {2, 3};
    expect(t, "degree drop to 2", c2, 4, -inf, inf, w2, 2, 1e-15, ALL);
    double c3[] = {-6, 11, -6, 1, 0}, w3[] = {1, 2, 3};
    expect(t, "degree drop to 3", c3, 4, -inf, inf, w3, 3, 1e-14, ALL);
    double c0[] = {3, 0, 0, 0, 0};
    expect(t, "constant", c0, 4, -inf, inf, NULL, 0, 0.0, ALL);
    double cz[] = {0, 0, 0, 0, 0};
    expect(t, "zero polynomial", cz, 4, -inf, inf, NULL, 0, 0.0, ALL);
    double cx[] = {0, 0, -1, 1, 0}, wx[] = {0, 1}; /* x^2 (x - 1): zero roots */
    expect(t, "zero root of multiplicity 2", cx, 4, -inf, inf, wx, 2, 1e-15, ALL);
}

/* bad input */
static void bad_input_has_no_roots(ctest *t)
{
    const double inf = INFINITY;
    double c1[] = {1, NAN, 1}, c2[] = {1, INFINITY, -1}, c3[] = {-1, 0, 1};
    expect(t, "NaN coefficient", c1, 2, -inf, inf, NULL, 0, 0.0, ALL);
    expect(t, "Inf coefficient", c2, 2, -inf, inf, NULL, 0, 0.0, ALL);
    expect(t, "lo > hi", c3, 2, 1.0, -1.0, NULL, 0, 0.0, ALL);
    expect(t, "NaN bound", c3, 2, NAN, 1.0, NULL, 0, 0.0, ALL);
    double r[IG_MAX_DEGREE];
    if (ig_real_roots(c3, -1, -inf, inf, IG_ROOTS_AUTO, r) != 0 ||
        ig_real_roots(c3, IG_MAX_DEGREE + 1, -inf, inf, IG_ROOTS_AUTO, r) != 0) {
        ctest_fail(t, "degree out of range accepted");
    }
}

/* tangent (even multiplicity) roots, exact in double */
static void tangent_roots_of_even_multiplicity(ctest *t)
{
    double c[IG_MAX_DEGREE + 3];
    const double inf = INFINITY;
    int n;
    double r[] = {1, 1, 3}, w[] = {1, 3};
    n = from_roots(r, 3, NULL, 0, 1.0, c);
    expect(t, "double root (x-1)^2 (x-3)", c, n, -inf, inf, w, 2, 1e-15, ALL);
    double r2[] = {0.5, 0.5, -2, -2}, w2[] = {-2, 0.5};
    n = from_roots(r2, 4, NULL, 0, 1.0, c);
    expect(t, "two double roots", c, n, -inf, inf, w2, 2, 1e-15, ALL);
    double r4[] = {1.25, 1.25, 1.25, 1.25}, w4[] = {1.25};
    n = from_roots(r4, 4, NULL, 0, 1.0, c);
    expect(t, "quadruple root", c, n, -inf, inf, w4, 1, 1e-15, NO_STURM);
    double r5[] = {0.75, 0.75, -1.5}, q5[][2] = {{-1, 0.5}}, w5[] = {-1.5, 0.75};
    n = from_roots(r5, 3, q5, 1, 1.0, c);
    /* found as the simple root of p' that it is: evaluating p' there errs by ~1e-15 relative */
    expect(t, "double root beside a complex pair", c, n, -inf, inf, w5, 2, 2e-15, ALL);
    double r6[] = {2, 2, 2, 2, -1, -1}, w6[] = {-1, 2};
    n = from_roots(r6, 6, NULL, 0, 1.0, c);
    expect(t, "degree 6: quadruple and double", c, n, -inf, inf, w6, 2, 1e-15, NO_STURM);
}

/* real roots spread over 150 decades next to the overflow limit: c0 is about 1e307 */
static void roots_over_150_decades(ctest *t)
{
    double c[IG_MAX_DEGREE + 3];
    const double inf = INFINITY;
    int n;
    double r[] = {1, 10, 1e152, 1e154};
    n = from_roots(r, 4, NULL, 0, 1.0, c);
    expect(t, "roots 1, 10, 1e152, 1e154", c, n, -inf, inf, r, 4, 1e-13, GENERAL);
    double r2[] = {-1e154, -3, 2, 1e150}, w2[] = {-1e154, -3, 2, 1e150};
    n = from_roots(r2, 4, NULL, 0, 1.0, c);
    expect(t, "roots -1e154, -3, 2, 1e150", c, n, -inf, inf, w2, 4, 1e-13, GENERAL);
}

/* a tiny positive minimum is not a root */
static void a_tiny_positive_minimum_is_not_a_root(ctest *t)
{
    double c[IG_MAX_DEGREE + 3];
    const double inf = INFINITY;
    int n;
    double q[][2] = {{-2, 1 + 0x1p-40}}, r[] = {-3};
    n = from_roots(NULL, 0, q, 1, 1.0, c);
    expect(t, "tiny minimum, quadratic", c, n, -inf, inf, NULL, 0, 0.0, ALL);
    n = from_roots(r, 1, q, 1, 1.0, c);
    expect(t, "tiny minimum beside a root", c, n, -inf, inf, r, 1, 1e-15, ALL);
    double q2[][2] = {{-2, 1 + 0x1p-52}, {0, 4}};
    n = from_roots(NULL, 0, q2, 2, 1.0, c);
    expect(t, "minimum 2^-52 (quartic)", c, n, -inf, inf, NULL, 0, 0.0, ALL);
}

/* clusters */
static void clusters(ctest *t)
{
    double c[IG_MAX_DEGREE + 3];
    const double inf = INFINITY;
    int n;
    double r[] = {1.0, 1.001, 1.002, 1.003};
    n = from_roots(r, 4, NULL, 0, 1.0, c);
    /* the decimal roots are not exact in the double coefficients: condition ~1e8 x 2^-53 */
    expect(t, "cluster 1.000..1.003", c, n, -inf, inf, r, 4, 1e-6, ALL);
    double r6[] = {1.0, 1.001, 1.002, 1.003, -2.0, 5.0}, w6[] = {-2.0, 1.0, 1.001, 1.002, 1.003, 5.0};
    n = from_roots(r6, 6, NULL, 0, 1.0, c);
    expect(t, "cluster in degree 6", c, n, -inf, inf, w6, 6, 1e-6, ALL);
}

/* scale */
static void coefficient_scale(ctest *t)
{
    double c[IG_MAX_DEGREE + 3];
    const double inf = INFINITY;
    int n;
    double r[] = {-1.5, 0.25, 2, 3};
    n = from_roots(r, 4, NULL, 0, 1e150, c);
    expect(t, "coefficients ~1e150", c, n, -inf, inf, r, 4, 1e-14, ALL);
    n = from_roots(r, 4, NULL, 0, 1e-150, c);
    expect(t, "coefficients ~1e-150", c, n, -inf, inf, r, 4, 1e-14, ALL);
    n = from_roots(r, 4, NULL, 0, 1e300, c);
    expect(t, "coefficients ~1e300", c, n, -inf, inf, r, 4, 1e-14, ALL);
    double s[] = {-1e30, 1e-30, 1.0};
    n = from_roots(s, 3, NULL, 0, 1.0, c);
    double ws[] = {-1e30, 1e-30, 1.0};
    expect(t, "roots 1e-30 .. 1e30", c, n, -inf, inf, ws, 3, 1e-14, GENERAL); /* closed, Sturm: documented limits */
    double h[] = {1e100, -3.0, 1e-100, 7.0}, wh[] = {-3.0, 1e-100, 7.0, 1e100};
    n = from_roots(h, 4, NULL, 0, 1.0, c);
    expect(t, "root 1e100 (reversed-polynomial range)", c, n, -inf, inf, wh, 4, 1e-14, GENERAL);
}

/* high degree products of known factors */
static void high_degree_products(ctest *t)
{
    double c[IG_MAX_DEGREE + 3];
    const double inf = INFINITY;
    int n;
    double r[] = {-2.5, -1.25, -0.5, 0.375, 1.5, 2.75}, q[][2] = {{0, 1}, {-1, 2}, {2, 5}, {0.5, 0.5}, {-3, 3}, {1, 1}};
    n = from_roots(r, 6, q, 6, 1.0, c); /* degree 18 */
    expect(t, "degree 18: 6 real, 6 complex pairs", c, n, -inf, inf, r, 6, 1e-10, ALL);
    double q9[][2] = {{0, 1}, {-1, 2}, {2, 5}, {0.5, 0.5}, {-3, 3}, {1, 1}, {0, 2}, {1.5, 1}, {-0.5, 1}};
    n = from_roots(r, 6, q9, 9, 1.0, c); /* degree 24 */
    expect(t, "degree 24: 6 real, 9 complex pairs", c, n, -inf, inf, r, 6, 1e-9, ALL);
    double r12[] = {-3, -2.5, -2, -1.5, -1, -0.5, 0.5, 1, 1.5, 2, 2.5, 3};
    n = from_roots(r12, 12, NULL, 0, 1.0, c);
    expect(t, "degree 12: 12 real roots", c, n, -inf, inf, r12, 12, 1e-9, ALL);
    double w[] = {-1, -0.5, 0.5, 1};
    /* Sturm: its floating-point count goes wrong here (see docs/solvers.md) */
    expect(t, "degree 12 on [-1, 1]", c, n, -1.0, 1.0, w, 4, 1e-9, NO_STURM);
}

/* first-root cases (every expect() above also checks ig_first_root) */
static void first_root_cases(ctest *t)
{
    double c[IG_MAX_DEGREE + 3];
    const double inf = INFINITY;
    int n;
    double r[] = {1, 2, 3, 4};
    n = from_roots(r, 4, NULL, 0, 1.0, c);
    expect(t, "root exactly at hi only", c, n, 1.5, 2.0, r + 1, 1, 0.0, ALL);
    expect(t, "root exactly at hi only, lo = -inf", c, n, -inf, 1.0, r, 1, 0.0, ALL);
    expect(t, "lo == hi between roots", c, n, 2.5, 2.5, NULL, 0, 0.0, ALL);
    double tg[] = {1, 1, 3, 4}, wt[] = {1, 3, 4};
    n = from_roots(tg, 4, NULL, 0, 1.0, c);
    /* x^4 - 9x^3 + 27x^2 - 31x + 12: at the simple root 3, sum |c_k| 3^k / (3 |p'(3)|) = 672 / 12 = 56, so
     * any method that evaluates p in double can be off by ~56 u = 6e-15 relative there */
    expect(t, "tangent root first", c, n, -inf, inf, wt, 3, 1e-14, ALL);
    double t2[] = {1, 3, 3}, wt2[] = {1, 3};
    n = from_roots(t2, 3, NULL, 0, 1.0, c);
    expect(t, "simple root before a tangent root", c, n, -inf, inf, wt2, 2, 1e-15, ALL);
    /* 1 and 1 + 2^-17 are exact in the coefficients. The pair is ill-conditioned: near it p is below
     * ~1e-10 while Horner's rounding noise is ~1e-13, so every method places the two roots only to
     * ~5e-11 (measured); 2e-10 relative is well below half their gap (3.8e-6). A gap of 2^-30 would be
     * below what double evaluation can resolve at all (p ~ 1e-19 there, under the noise). */
    double cl[] = {1, 1 + 0x1p-17, 2, 3, -4, 5}, wcl[] = {1, 1 + 0x1p-17, 2, 3, 5};
    n = from_roots(cl, 6, NULL, 0, 1.0, c);
    expect(t, "first root 2^-17 from the second", c, n, 0.5, inf, wcl, 5, 2e-10, ALL);
    double tiny[] = {1e-30, 1, 2};
    n = from_roots(tiny, 3, NULL, 0, 1.0, c);
    expect(t, "first root 1e-30, others near 1", c, n, 0.0, inf, tiny, 3, 1e-14, ALL);
    double cz[] = {0, -1, 0, 1}, wz[] = {-1, 0, 1}; /* x (x - 1) (x + 1) */
    expect(t, "zero root, lo < 0", cz, 3, -inf, inf, wz, 3, 1e-15, ALL);
    expect(t, "zero root, lo = -0.5", cz, 3, -0.5, inf, wz + 1, 2, 1e-15, ALL);
    expect(t, "zero root, lo = 0", cz, 3, 0.0, inf, wz + 1, 2, 1e-15, ALL);
    expect(t, "zero root just below lo", cz, 3, 0x1p-1000, inf, wz + 2, 1, 1e-15, ALL);
    for (int m = 0; m < NMETHODS; ++m) { /* the zero root is +0, never -0 */
        double z = -1.0;
        if (!ig_first_root(cz, 3, -0.5, 0.5, (ig_root_method)m, &z) || z != 0.0 || signbit(z)) {
            ctest_fail(t, "first root 0 is not +0 [%s]: %.17g", method_names[m], z);
        }
    }
    double bad[] = {1, NAN, 1}, badi[] = {-1, 0, -INFINITY}, ok2[] = {-1, 0, 1};
    expect(t, "first root of NaN coefficients", bad, 2, -inf, inf, NULL, 0, 0.0, ALL);
    expect(t, "first root of Inf coefficients", badi, 2, -inf, inf, NULL, 0, 0.0, ALL);
    expect(t, "hi NaN", ok2, 2, -inf, NAN, NULL, 0, 0.0, ALL);
    double f = 7.0;
    if (ig_first_root(ok2, -1, -inf, inf, IG_ROOTS_AUTO, &f) != 0 ||
        ig_first_root(ok2, IG_MAX_DEGREE + 1, -inf, inf, IG_ROOTS_AUTO, &f) != 0 || f != 7.0) {
        ctest_fail(t, "first root: degree out of range accepted");
    }
}

/* the yes/no query on simple dyadic roots (exact coefficients) over random dyadic intervals, so
 * that Bernstein certifies pieces and answers with unrefined points */
static void any_root_on_random_dyadic_intervals(ctest *t)
{
    int n;
    unsigned long long st = 12345;
    int unrefined = 0, queries = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        double r[8], quad[3][2], w[8], lo, hi, c1[IG_MAX_DEGREE + 3], first = NAN, any = NAN;
        int nr = 1 + (int)(trial % 5), nq = (int)(trial / 5 % 3), nw = 0;
        for (int i = 0; i < nr; ++i) {
            int again;
            do { /* distinct multiples of 1/8 in [-2, 2] */
                st = st * 6364136223846793005ULL + 1442695040888963407ULL;
                r[i] = (double)((int)(st >> 33) % 33 - 16) / 8.0;
                again = 0;
                for (int j = 0; j < i; ++j)
                    again |= r[j] == r[i];
            } while (again);
        }
        for (int i = 0; i < nq; ++i) { /* x^2 + b x + q without real roots */
            quad[i][0] = 0.25 * (double)(i + 1);
            quad[i][1] = 0.5 + 0.5 * (double)i;
        }
        n = from_roots(r, nr, quad, nq, 1.0, c1);
        st = st * 6364136223846793005ULL + 1442695040888963407ULL;
        lo = (double)((int)(st >> 33) % 65 - 40) / 16.0 + 1.0 / 32.0; /* never a root */
        st = st * 6364136223846793005ULL + 1442695040888963407ULL;
        hi = lo + (double)(1 + (int)(st >> 33) % 64) / 16.0;
        for (int i = 0; i < nr; ++i) /* sorted wanted roots inside [lo, hi] */
            if (r[i] >= lo && r[i] <= hi) {
                int k = nw++;
                while (k > 0 && w[k - 1] > r[i]) {
                    w[k] = w[k - 1];
                    --k;
                }
                w[k] = r[i];
            }
        for (int m = 0; m < NMETHODS; ++m) {
            if (!((1 << m) & GENERAL))
                continue;
            check_any(t, "random dyadic", c1, n, lo, hi, w, nw, m);
            ++queries;
            if (m == IG_ROOTS_BERNSTEIN && nw > 0 && ig_roots_core(c1, n, lo, hi, m, IG_ANY_ROOT, &any) == 1 &&
                ig_first_root(c1, n, lo, hi, (ig_root_method)m, &first) == 1 && any != first)
                ++unrefined;
        }
    }
    if (unrefined < 1000) {
        ctest_fail(t, "any root: only %d unrefined answers (the certified-piece path untested)", unrefined);
    }
    printf("any root: %d queries, %d answered by Bernstein with an unrefined point\n", queries, unrefined);
}

/* The yes/no query answers as soon as two certified signs differ, without isolating a root: the middle of the
 * first such pair among the ends and the middle of [lo, hi], and p's value at 0 (where the tracer's ray polynomial
 * is expanded) when 0 lies inside. Each answer is that middle, strictly inside an interval that holds a root. */
static void any_root_stops_at_a_sign_change(ctest *t)
{
    double r1[] = {-0.75, 0.25, 0.5}, r2[] = {-0.5, 0.5, 3.0}, c[IG_MAX_DEGREE + 3], x = NAN;
    int n = from_roots(r1, 3, NULL, 0, 1.0, c); /* p(-1) < 0 < p(0): the left end and the middle differ */
    CHECKF(t, ig_roots_core(c, n, -1.0, 1.0, IG_ROOTS_BERNSTEIN, IG_ANY_ROOT, &x) == 1 && x == -0.5,
           "ends of opposite sign: %.17g, not the middle of [-1, 0]", x);
    n = from_roots(r2, 3, NULL, 0, 1.0, c); /* on [-1, 2.5] p(-1), p(0.75), p(2.5) < 0 < p(0) */
    CHECKF(t, ig_roots_core(c, n, -1.0, 2.5, IG_ROOTS_BERNSTEIN, IG_ANY_ROOT, &x) == 1 && x == -0.5,
           "p(0) against the ends: %.17g, not the middle of [-1, 0]", x);
    CHECKF(t, ig_roots_core(c, n, 0.75, 2.5, IG_ROOTS_BERNSTEIN, IG_ANY_ROOT, &x) == 0, "a root where none is");
}

static const ctest_case CASES[] = {
    CTEST_CASE(four_simple_roots),
    CTEST_CASE(degree_drops_when_leading_coefficients_vanish),
    CTEST_CASE(bad_input_has_no_roots),
    CTEST_CASE(tangent_roots_of_even_multiplicity),
    CTEST_CASE(roots_over_150_decades),
    CTEST_CASE(a_tiny_positive_minimum_is_not_a_root),
    CTEST_CASE(clusters),
    CTEST_CASE(coefficient_scale),
    CTEST_CASE(high_degree_products),
    CTEST_CASE(first_root_cases),
    CTEST_CASE(any_root_on_random_dyadic_intervals),
    CTEST_CASE(any_root_stops_at_a_sign_change),
};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
