/* Real roots of a polynomial on a closed interval: the public entry points and the dispatcher in front of
 * the methods (roots_closed.c, roots_sturm.c, roots_bracket.c, roots_bernstein.c; the pieces they share are
 * in roots_common.c and roots_refine.c).
 *
 * Pipeline of ig_real_roots (every method goes through it):
 *   1. reject bad input (NaN/Inf coefficients or bounds, lo > hi, degree out of range): no roots;
 *   2. lower the degree while the leading coefficient is exactly zero, and take out exact zero roots
 *      (trailing zero coefficients), so the solvers always see p(0) != 0 and p[n] != 0;
 *   3. rescale the coefficients by a power of two (exact) when they are beyond 2^+-200, so nothing overflows;
 *   4. degree 1 and 2 are solved in closed form by every method; above that the chosen method runs;
 *   5. an infinite bound is replaced by a root bound; when |x|^n could overflow, the range |x| > 1 is solved
 *      on the reversed polynomial x^n p(1/x) in y = 1/x, which keeps every evaluation in range;
 *   6. the results are sorted, exact duplicates dropped, and only finite roots inside [lo, hi] kept.
 */
#include "roots_impl.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>

/* ---------------------------------------------------------------- interval handling */

/* The chosen method on a finite [a, b] (method: sturm, bracket or bernstein; first: first-root mode where the
 * method has one; fallbacks: NULL or the Bernstein statistics counter). */
static int solve_interval(int method, int first, int *fallbacks, const double *p, int n, double a, double b,
                          double *out)
{
    switch (method) {
    case IG_ROOTS_STURM:
        return ig_sturm_interval(p, n, a, b, out);
    case IG_ROOTS_BERNSTEIN:
        if (first == IG_ANY_ROOT)
            return ig_bernstein_any(p, n, a, b, fallbacks, out);
        return first ? ig_bernstein_first(p, n, a, b, fallbacks, out)
                     : ig_bernstein_interval(p, n, a, b, fallbacks, out);
    default:
        return ig_bracket_roots(p, n, a, b, first, out);
    }
}

/* Fujiwara's bound 2 max_k |p[n-k] / p[n]|^(1/k) (with p[0] / 2), rounded up to a power of two using only
 * the binary exponents: cheap and never overflows (DBL_MAX when the bound is not representable). */
static double root_bound(const double *p, int n)
{
    int en = ilogb(p[n]);
    int best = INT32_MIN;
    for (int k = 1; k <= n; ++k) {
        double ck = p[n - k];
        if (ck == 0.0)
            continue;
        /* |ck / p[n]| < 2^(ilogb(ck) - en + 1); its k-th root < 2^ceil((ilogb(ck) - en + 1) / k) */
        int num = ilogb(ck) - en + 1 - (k == n ? 1 : 0);
        int e = num >= 0 ? (num + k - 1) / k : -((-num) / k);
        if (e > best)
            best = e;
    }
    if (best == INT32_MIN)
        return 0.0;
    if (best + 1 > DBL_MAX_EXP - 1)
        return DBL_MAX;
    return ldexp(1.0, best + 1);
}

/* first != 0 uses the method's first-root mode where the interval is solved in one piece. */
static int solve_general(const double *p, int n, double lo, double hi, int method, int first, int *fallbacks,
                         double *out)
{
    double a = lo, b = hi;
    if (isinf(a) || isinf(b)) {
        double bound = root_bound(p, n);
        if (a < -bound)
            a = -bound;
        if (b > bound)
            b = bound;
        if (a > b)
            return 0;
    }
    double big = ig_max(fabs(a), fabs(b));
    /* coefficients are at most ~2^200 (see ig_real_roots_any); |x|^n below 2^524 keeps Horner and the
     * splitting of Dekker's product (another 2^27) far from overflow */
    if (big <= 0x1p20 || (double)n * ilogb(big) < 500.0) /* n <= 24: 2^20 is always safe */
        return solve_interval(method, first, fallbacks, p, n, a, b, out);

    /* |x| > 1 on the reversed polynomial q(y) = y^n p(1/y), y = 1/x in [-1, 1] */
    double q[IG_MAX_DEGREE + 1], tmp[IG_ROOT_BUF];
    for (int k = 0; k <= n; ++k)
        q[k] = p[n - k];
    int cnt = 0;
    if (a <= 1.0 && b >= -1.0)
        cnt = solve_interval(method, 0, fallbacks, p, n, fmax(a, -1.0), fmin(b, 1.0), out);
    if (b > 1.0) {
        double xa = fmax(a, 1.0);
        int k = solve_interval(method, 0, fallbacks, q, n, 1.0 / b, 1.0 / xa, tmp);
        for (int i = 0; i < k; ++i) {
            double x = 1.0 / tmp[i];
            if (x >= a && x <= b) /* x = 1 from both parts: one is dropped as a duplicate */
                out[cnt++] = x;
        }
    }
    if (a < -1.0) {
        double xb = fmin(b, -1.0);
        int k = solve_interval(method, 0, fallbacks, q, n, 1.0 / xb, 1.0 / a, tmp);
        for (int i = 0; i < k; ++i) {
            double x = 1.0 / tmp[i];
            if (x >= a && x <= b)
                out[cnt++] = x;
        }
    }
    return ig_sort_unique(out, cnt);
}

/* Newton's inequalities: when every root of p (degree n) is real, a_k = p[k] / C(n, k) is log-concave,
 * a_k^2 >= a_(k-1) a_(k+1), i.e. p[k]^2 k (n - k) >= p[k-1] p[k+1] (k + 1) (n - k + 1). Used as the test "all
 * roots may be real" (necessary, not sufficient; a product that underflows only makes it pass). */
static int newton_inequalities(const double *p, int n)
{
    int fail = 0; /* no early exit: one branch on the outcome, not one per k */
    for (int k = 1; k < n; ++k)
        fail |= p[k] * p[k] * (double)(k * (n - k)) < p[k - 1] * p[k + 1] * (double)((k + 1) * (n - k + 1));
    return !fail;
}

/* The method `auto` uses (after deflating zero roots); the solver report (`implgen bench solvers`) is where
 * this choice comes from. Bernstein subdivision, except on the whole line at degree <= AUTO_BRACKET_DEGREE when
 * Newton's inequalities hold: then all roots may be real, and every one of them needs its own isolation by
 * subdivision from the root bound down, which a multiple root, a cluster or roots at very different scales
 * never reach (bracketing on the derivatives is scale-free and reports tangent roots directly). Both modes
 * must take the same method (first-root mode returns bitwise the full list's first root), and the cap is where
 * the two modes' preferences meet: in all-roots mode bracketing wins on such polynomials up to degree 7, but in
 * first-root mode the subdivision stops at the leftmost root and wins from degree 7 on (a quadruple root beside
 * a complex pair: 0.5 us against 2.4 us), so above degree 6 the subdivision keeps them. */
#define AUTO_BRACKET_DEGREE 6
static int auto_method(const double *p, int n, double lo, double hi)
{
    if (n <= AUTO_BRACKET_DEGREE && isinf(lo) && isinf(hi) && newton_inequalities(p, n))
        return IG_ROOTS_BRACKET;
    return IG_ROOTS_BERNSTEIN;
}

static int solve_reduced(const double *p, int n, double lo, double hi, int method, int first, int *fallbacks,
                         double *out)
{
    if (n == 1) {
        double x = -p[0] / p[1];
        if (!isfinite(x))
            return 0;
        out[0] = x;
        return 1;
    }
    if (n == 2)
        return ig_quadratic(p[0], p[1], p[2], out);
    if (method == IG_ROOTS_AUTO)
        method = auto_method(p, n, lo, hi);
    switch (method) {
    case IG_ROOTS_CLOSED:
    case IG_ROOTS_CLOSED_PLAIN: {
        int polish = method == IG_ROOTS_CLOSED;
        if (n == 3)
            return ig_closed_cubic(p, lo, hi, polish, out);
        if (n == 4)
            return ig_closed_quartic(p, lo, hi, polish, out);
        return solve_general(p, n, lo, hi, IG_ROOTS_BRACKET, 0, NULL, out);
    }
    case IG_ROOTS_STURM:
    case IG_ROOTS_BRACKET:
    case IG_ROOTS_BERNSTEIN:
        return solve_general(p, n, lo, hi, method, first, fallbacks, out);
    default:
        return 0;
    }
}

int ig_roots_core(const double *c, int n, double lo, double hi, int method, int first, double *roots)
{
    return ig_roots_stats(c, n, lo, hi, method, first, NULL, roots);
}

int ig_roots_stats(const double *c, int n, double lo, double hi, int method, int first, int *fallbacks, double *roots)
{
    if (!c || !roots || n < 0 || n > IG_MAX_DEGREE)
        return 0;
    if (n <= 2) /* a plane, a quadric: the closed forms, every method alike (roots_impl.h) */
        return ig_roots_low(c, n, lo, hi, first, roots);
    if (!(lo <= hi)) /* also NaN bounds */
        return 0;
    double cmax = 0.0;
    for (int k = 0; k <= n; ++k) {
        double m = fabs(c[k]);
        if (!(m <= DBL_MAX)) /* NaN or Inf */
            return 0;
        cmax = m > cmax ? m : cmax;
    }
    if (cmax == 0.0)
        return 0; /* the zero polynomial: every t is a root; reported as none */
    double scaled[IG_MAX_DEGREE + 1];
    const double *p = c;
    /* exact rescaling by a power of two when the coefficients are far from 1 */
    if (cmax > 0x1p200 || cmax < 0x1p-200) {
        int e = ilogb(cmax);
        double s1 = ldexp(1.0, -e / 2), s2 = ldexp(1.0, -e - (-e / 2));
        for (int k = 0; k <= n; ++k)
            scaled[k] = (c[k] * s1) * s2;
        p = scaled;
    }
    int top = n;
    while (top > 0 && p[top] == 0.0)
        --top;
    int m = 0; /* multiplicity of the root t = 0 */
    while (m < top && p[m] == 0.0)
        ++m;
    int deg = top - m;
    double r[IG_ROOT_BUF];
    int k = 0;
    if (deg > 0)
        k = solve_reduced(p + m, deg, lo, hi, method, first, fallbacks, r);
    if (m > 0)
        r[k++] = 0.0;
    if (k > 1 && (deg != 2 || m > 0)) /* ig_quadratic lists its roots ascending and distinct already */
        k = ig_sort_unique(r, k);
    int cnt = 0, most = first ? 1 : n;
    for (int i = 0; i < k && cnt < most; ++i)
        if (r[i] >= lo && r[i] <= hi && isfinite(r[i]))
            roots[cnt++] = r[i] == 0.0 ? 0.0 : r[i]; /* no -0 */
    return cnt;
}

int ig_real_roots_any(const double *c, int n, double lo, double hi, int method, double *roots)
{
    return ig_roots_core(c, n, lo, hi, method, 0, roots);
}

int ig_real_roots(const double *c, int n, double lo, double hi, ig_root_method method, double *roots)
{
    return ig_roots_core(c, n, lo, hi, (int)method, 0, roots);
}

int ig_first_root(const double *c, int n, double lo, double hi, ig_root_method method, double *root)
{
    return ig_roots_core(c, n, lo, hi, (int)method, 1, root);
}

void ig_real_roots_batch(const double *c, int n, long count, const double *lo, const double *hi, int method,
                         double *roots, int *counts)
{
    double r[IG_MAX_DEGREE];
    for (long i = 0; i < count; ++i) {
        int k = ig_real_roots_any(c + i * (n + 1), n, lo[i], hi[i], method, r);
        counts[i] = k;
        for (int j = 0; j < n; ++j)
            roots[i * n + j] = j < k ? r[j] : NAN;
    }
}

void ig_first_root_batch(const double *c, int n, long count, const double *lo, const double *hi, int method,
                         double *roots, int *counts)
{
    for (long i = 0; i < count; ++i) {
        double r = NAN;
        counts[i] = ig_roots_core(c + i * (n + 1), n, lo[i], hi[i], method, 1, &r);
        roots[i] = counts[i] ? r : NAN;
    }
}
