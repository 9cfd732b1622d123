/* Real roots of a polynomial on a closed interval: the dispatcher, the shared numerics (certified sign,
 * refinement of a bracketed root, stable quadratic) and the derivative-bracketing method.
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
 *
 * Refinement (ig_refine, ig_refine_many): a bracketed simple root by Householder's third-order step, with
 * bisection and, for anything unusual, an rtsafe-style safeguarded Newton behind it; brackets of one
 * polynomial are refined four at a time, so that their evaluation chains overlap.
 *
 * Derivative bracketing (in the spirit of Yuksel 2022): the roots of p^(n-2) (a quadratic) cut [lo, hi]
 * into pieces where p^(n-3) is monotonic; each sign change there is one root, found by the refinement;
 * those roots cut the interval for p^(n-4), and so on up to p. A piece end where p is zero within rounding
 * (certified by a compensated evaluation) is reported as a root: that is how a tangent (even multiplicity)
 * root, which has no sign change, is found, and why a tiny positive minimum is not.
 */
#include "roots_impl.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

/* ---------------------------------------------------------------- error-free transformations */

static void two_sum(double a, double b, double *s, double *e)
{
    double x = a + b;
    double z = x - a;
    *e = (a - (x - z)) + (b - z);
    *s = x;
}

/* Dekker's product without FMA (the library is built for baseline x86-64, where fma() is a slow call). */
static void two_prod(double a, double b, double *p, double *e)
{
    const double split = 134217729.0; /* 2^27 + 1 */
    double x = a * b;
    double fa = split * a, fb = split * b;
    double ah = fa - (fa - a), al = a - ah;
    double bh = fb - (fb - b), bl = b - bh;
    *e = al * bl - (((x - ah * bh) - al * bh) - ah * bl);
    *p = x;
}

/* ---------------------------------------------------------------- evaluation */

void ig_horner2(const double *c, int n, double x, double *p, double *dp)
{
    if (n == 4) { /* the torus case, unrolled: same operations, no loop overhead */
        double v = c[4] * x + c[3], d = c[4];
        d = d * x + v;
        v = v * x + c[2];
        d = d * x + v;
        v = v * x + c[1];
        d = d * x + v;
        *p = v * x + c[0];
        *dp = d;
        return;
    }
    if (n == 3) {
        double v = c[3] * x + c[2], d = c[3];
        d = d * x + v;
        v = v * x + c[1];
        d = d * x + v;
        *p = v * x + c[0];
        *dp = d;
        return;
    }
    double v = c[n], d = 0.0;
    for (int k = n - 1; k >= 0; --k) {
        d = d * x + v;
        v = v * x + c[k];
    }
    *p = v;
    *dp = d;
}

static double horner(const double *c, int n, double x)
{
    double v = c[n];
    for (int k = n - 1; k >= 0; --k)
        v = v * x + c[k];
    return v;
}

int ig_sign_certified(const double *c, int n, double x, double *val)
{
    double v = c[n], s = fabs(c[n]), ax = fabs(x);
    for (int k = n - 1; k >= 0; --k) {
        v = v * x + c[k];
        s = s * ax + fabs(c[k]);
    }
    double g = 2.0 * n * IG_U;
    g = g / (1.0 - g); /* gamma_2n: a priori bound of Horner's relative error against sum |c_k||x|^k */
    double tiny = 2.0 * (n + 1) * DBL_MIN * IG_U; /* underflow allowance */
    *val = v;
    if (fabs(v) > g * s + tiny)
        return v > 0.0 ? 1 : -1;
    /* Compensated Horner (Graillat, Langlois, Louvet 2005): as accurate as Horner in twice the precision. */
    double r = c[n], err = 0.0;
    for (int k = n - 1; k >= 0; --k) {
        double pr, pe, se;
        two_prod(r, x, &pr, &pe);
        two_sum(pr, c[k], &r, &se);
        err = err * x + (pe + se);
    }
    double res = r + err;
    *val = res;
    if (fabs(res) > 2.0 * IG_U * fabs(res) + 2.0 * g * g * s + tiny)
        return res > 0.0 ? 1 : -1;
    return 0;
}

/* ---------------------------------------------------------------- safeguarded Newton */

/* Doubles mapped to integers that keep their order (-0 and +0 both map to 0). */
static int64_t ordered(double x)
{
    int64_t i;
    memcpy(&i, &x, sizeof i);
    return i >= 0 ? i : INT64_MIN - i;
}

static double unordered(int64_t i)
{
    double x;
    if (i < 0)
        i = INT64_MIN - i;
    memcpy(&x, &i, sizeof x);
    return x;
}

/* Midpoint in the ordering of doubles: halves the number of doubles in the bracket, so bisection alone
 * reaches adjacent doubles in at most 64 steps whatever the magnitudes (a root at 1e-300 in [-1, 1]). */
double ig_ordered_mid(double l, double r)
{
    int64_t a = ordered(l), b = ordered(r);
    uint64_t diff = (uint64_t)b - (uint64_t)a;
    return unordered(a + (int64_t)(diff / 2u));
}

static double refine_safe(const double *c, int n, double l, double r, double vl, double vr, double tol, double x0)
{
    const int positive_left = vl > 0.0;
    /* start from the caller's guess, else the false-position point (exact for a line) */
    double x = x0;
    if (!(x > l && x < r))
        x = l - vl * ((r - l) / (vr - vl));
    if (!(x > l && x < r))
        x = ig_ordered_mid(l, r);
    /* As in rtsafe: a Newton step is taken only when it stays inside the bracket and is less than half the
     * step before the last one; otherwise bisect. Far from the root (|x|^n growth on a wide piece) Newton
     * crawls, and bisection in the ordering of doubles gets there in a few steps instead. */
    double dx = INFINITY, dxold = INFINITY;
    int newton_before = 0; /* was the last step a Newton step (so dx tells the convergence rate)? */
    for (int it = 0; it < 100; ++it) {
        double v, dv;
        ig_horner2(c, n, x, &v, &dv);
        if (v == 0.0)
            return x;
        if ((v > 0.0) == positive_left)
            l = x;
        else
            r = x;
        double step = v / dv, xn = x - step;
        double as = fabs(step), ax = fabs(x);
        /* converged (the step may even round away) -- unless the step leaves the bracket: then it heads for a
         * root beyond the bracket's end (p is tiny here because one lies just outside), and we bisect */
        if (as <= 4.0 * IG_U * ax && xn >= l && xn <= r)
            return xn;
        /* Newton converging only linearly while its steps are still a sizeable fraction of x (|x|^n growth
         * on a wide piece: a root at 1e-13 approached from 1e27 by halvings) -> bisect in the ordering of
         * doubles. Near a multiple root of an intermediate derivative the steps are soon tiny relative to x,
         * and Newton's linear convergence there is left alone (bisection would stop it early). */
        int slow = newton_before && as > 0.4 * fabs(dx) && as > 1e-3 * fabs(xn);
        if (!(xn > l && xn < r) || !(as <= 0.5 * fabs(dxold)) || slow) { /* also catches dv == 0, NaN */
            xn = ig_ordered_mid(l, r);
            if (!(xn > l && xn < r))
                return x; /* l and r are adjacent doubles */
            dxold = dx;
            dx = xn - x;
            newton_before = 0;
        } else {
            /* Newton's error after this step is about K step^2 with K = |step| / dx^2 estimated from the
             * last two steps: stop when that is below the tolerance (saves the confirming evaluation) */
            if (newton_before && as <= 1e-3 * fabs(dx) && as <= 1e-3 * fabs(xn) && (as / dx) * (as / dx) * as <= tol * fabs(xn))
                return xn;
            /* steps stopped shrinking while already tiny: they are rounding noise of p(x), which is as
             * close as this root can be resolved (or a multiple root, converging linearly) */
            if (newton_before && as > 0.5 * fabs(dx) && as <= 1e-9 * fabs(xn))
                return xn;
            dxold = dx;
            dx = step;
            newton_before = 1;
        }
        x = xn;
    }
    return x;
}

/* p(x), p'(x), p''(x) / 2 and p^(3)(x) / 6 at K points x[j] into e[4j .. 4j+3], by one Horner pass: 4K
 * independent chains, so K roots are refined in about the time of one (evaluation is latency-bound). Always
 * inlined with a constant K (1, 2, 4), so the compiler keeps the chains in registers; the operations for each
 * point are the same whatever K is, which is what makes ig_refine_many equal to ig_refine lane by lane. */
static inline void horner4(const double *c, int n, const double *x, double *e, const int K)
{
    double v[4], d[4], dd[4], d3[4];
    for (int j = 0; j < K; ++j) {
        v[j] = c[n];
        d[j] = dd[j] = d3[j] = 0.0;
    }
    for (int k = n - 1; k >= 0; --k)
        for (int j = 0; j < K; ++j) {
            d3[j] = d3[j] * x[j] + dd[j];
            dd[j] = dd[j] * x[j] + d[j];
            d[j] = d[j] * x[j] + v[j];
            v[j] = v[j] * x[j] + c[k];
        }
    for (int j = 0; j < K; ++j) {
        e[4 * j] = v[j];
        e[4 * j + 1] = d[j];
        e[4 * j + 2] = dd[j];
        e[4 * j + 3] = d3[j];
    }
}

/* The fast path of the refinement: Householder's third-order step on a simple root, kept inside the bracket,
 *     x - p (p'^2 - p p''/2) / (p'^3 - p p' p'' + p^2 p'''/6),
 * which converges with order four (Halley's step, one order lower, drops the p^2 p''' term). p''' costs a
 * fourth Horner chain that runs alongside the others, and evaluation is latency-bound, so a step costs about
 * what a Newton step does: from a start two digits right the error goes 1e-2 -> 1e-8 -> 1e-32, so two
 * evaluations give full accuracy where Newton's 1e-2 -> 1e-4 -> 1e-8 -> 1e-16 needs four. It stops when the
 * step is at rounding level, or when the error it predicts for the new iterate, |step| q^4 with q = |step| /
 * |previous step| (order-four convergence, constant estimated from the last two steps), is below the tolerance
 * -- trusted only once the iterate is in the asymptotic range: q <= 1e-3 and the step below 1e-3 |x| (a first
 * step from far away says nothing about the error). A step that leaves the bracket or does not at least halve
 * is replaced by bisection of the bracket. Steps that shrink only linearly near the root (a multiple root,
 * rounding noise) and eight evaluations without convergence hand the narrowed bracket and the iterate to
 * refine_safe above, whose rules handle multiple roots, huge ranges and rounding noise. */
typedef struct {
    double x, l, r, vl, vr, prev;
    int positive_left;
} hh_lane;

enum { LANE_MORE, LANE_DONE, LANE_SAFE };

/* Start a lane on [l, r]; LANE_SAFE when no start point strictly inside exists. */
static inline int lane_start(hh_lane *s, double l, double r, double vl, double vr, double x0)
{
    s->l = l;
    s->r = r;
    s->vl = vl;
    s->vr = vr;
    s->positive_left = vl > 0.0;
    s->prev = INFINITY;
    s->x = x0;
    if (!(s->x > l && s->x < r))
        s->x = l - vl * ((r - l) / (vr - vl));
    return s->x > l && s->x < r ? LANE_MORE : LANE_SAFE;
}

/* One iteration given e = p, p', p''/2, p'''/6 at s->x: LANE_DONE with the root in *root, LANE_MORE or
 * LANE_SAFE. */
static inline int lane_step(hh_lane *s, const double *e, double tol, double *root)
{
    double v = e[0], d = e[1], hdd = e[2], h3 = e[3];
    double x = s->x;
    if (v == 0.0) {
        *root = x;
        return LANE_DONE;
    }
    if ((v > 0.0) == s->positive_left) {
        s->l = x;
        s->vl = v;
    } else {
        s->r = x;
        s->vr = v;
    }
    double d2 = d * d;
    double step = (v * (d2 - v * hdd)) / (d2 * d - 2.0 * v * d * hdd + v * v * h3), xn = x - step;
    double as = fabs(step);
    int ok = xn >= s->l && xn <= s->r; /* false also for NaN: a zero denominator */
    if (ok && as <= 4.0 * IG_U * fabs(xn)) {
        *root = xn;
        return LANE_DONE;
    }
    if (ok && s->prev < INFINITY) {
        double q = as / s->prev;
        if (q <= 1e-3 && as <= 1e-3 * fabs(xn) && (q * q) * (q * q) * as <= tol * fabs(xn)) {
            *root = xn;
            return LANE_DONE;
        }
        if (q > 0.1 && as <= 1e-3 * fabs(xn)) {
            /* near the root but converging only linearly: a multiple root (of an intermediate derivative, or
             * a tangent root of p itself) or rounding noise; the safeguarded Newton goes on from here */
            if (xn > s->l && xn < s->r)
                s->x = xn;
            return LANE_SAFE;
        }
        if (!(q <= 0.5))
            ok = 0;
    }
    if (!ok || !(xn > s->l && xn < s->r)) { /* bisect the bracket instead (a false start far from the root) */
        xn = 0.5 * (s->l + s->r);
        if (!(xn > s->l && xn < s->r)) { /* l and r are adjacent doubles */
            *root = x;
            return LANE_DONE;
        }
        as = INFINITY;
    }
    s->prev = as;
    s->x = xn;
    return LANE_MORE;
}

#define IG_FAST_ITERS 8

double ig_refine(const double *c, int n, double l, double r, double vl, double vr, double tol, double x0)
{
    hh_lane s;
    double root;
    if (lane_start(&s, l, r, vl, vr, x0) == LANE_MORE)
        for (int it = 0; it < IG_FAST_ITERS; ++it) {
            double e[4];
            horner4(c, n, &s.x, e, 1);
            int st = lane_step(&s, e, tol, &root);
            if (st == LANE_DONE)
                return root;
            if (st == LANE_SAFE)
                break;
        }
    return refine_safe(c, n, s.l, s.r, s.vl, s.vr, tol, s.x);
}

void ig_refine_many(const double *c, int n, int k, const double *l, const double *r, const double *vl,
                    const double *vr, double tol, const double *x0, double *roots)
{
    if (k == 1) {
        roots[0] = ig_refine(c, n, l[0], r[0], vl[0], vr[0], tol, x0[0]);
        return;
    }
    for (int g = 0; g < k; g += 4) {
        hh_lane s[4];
        int state[4], m = k - g < 4 ? k - g : 4;
        for (int j = 0; j < m; ++j)
            state[j] = lane_start(&s[j], l[g + j], r[g + j], vl[g + j], vr[g + j], x0[g + j]);
        for (int it = 0; it < IG_FAST_ITERS; ++it) {
            double x[4], e[16];
            int live = 0;
            for (int j = 0; j < 4; ++j) {
                x[j] = j < m && state[j] == LANE_MORE ? s[j].x : 0.0;
                live += j < m && state[j] == LANE_MORE;
            }
            if (!live)
                break;
            if (m <= 2)
                horner4(c, n, x, e, 2);
            else
                horner4(c, n, x, e, 4);
            for (int j = 0; j < m; ++j)
                if (state[j] == LANE_MORE)
                    state[j] = lane_step(&s[j], e + 4 * j, tol, &roots[g + j]);
        }
        for (int j = 0; j < m; ++j)
            if (state[j] != LANE_DONE)
                roots[g + j] = refine_safe(c, n, s[j].l, s[j].r, s[j].vl, s[j].vr, tol, s[j].x);
    }
}

/* ---------------------------------------------------------------- quadratic, sorting */

int ig_quadratic(double c0, double c1, double c2, double *r)
{
    double b = -0.5 * c1; /* roots of c2 x^2 - 2 b x + c0 are (b +- sqrt(b^2 - c2 c0)) / c2 */
    double bb = b * b, ac = c2 * c0;
    double d = bb - ac;
    if (fabs(d) <= 4.0 * IG_U * (bb + fabs(ac))) {
        /* cancellation: redo the discriminant with exact products (Kahan), so its sign is right and a
         * double root of the given coefficients comes out as d == 0 */
        double pb, eb, pa, ea;
        two_prod(b, b, &pb, &eb);
        two_prod(c2, c0, &pa, &ea);
        d = (pb - pa) + (eb - ea);
    }
    if (!(d >= 0.0))
        return 0;
    int k;
    if (d == 0.0) {
        r[0] = b / c2;
        k = 1;
    } else {
        double q = b + copysign(sqrt(d), b); /* no cancellation; q != 0 because d > 0 */
        double x1 = q / c2, x2 = c0 / q;
        if (x1 > x2) {
            double t = x1;
            x1 = x2;
            x2 = t;
        }
        r[0] = x1;
        r[1] = x2;
        k = (x1 == x2) ? 1 : 2;
    }
    int m = 0; /* a root beyond DBL_MAX is not representable: drop it */
    for (int i = 0; i < k; ++i)
        if (isfinite(r[i]))
            r[m++] = r[i];
    return m;
}

int ig_sort_unique(double *r, int k)
{
    for (int i = 1; i < k; ++i) {
        double x = r[i];
        int j = i - 1;
        while (j >= 0 && r[j] > x) {
            r[j + 1] = r[j];
            --j;
        }
        r[j + 1] = x;
    }
    int m = 0;
    for (int i = 0; i < k; ++i)
        if (m == 0 || r[i] != r[m - 1])
            r[m++] = r[i];
    return m;
}

/* ---------------------------------------------------------------- derivative bracketing */

/* A critical point x of p (root of p') where p is zero within rounding: a tangent root of some
 * multiplicity k >= 2. x came from p', whose root there has multiplicity k - 1, so it is only
 * ~u^(1/(k-1)) accurate; p^(k-1) has a simple root there. Newton on each derivative p^(j), j = 1..5, from x
 * (kept inside (l, r)); the candidate wins where p is zero within rounding (certified sign), then where
 * Newton settled (a simple root of p^(j): those on p^(j), j < k - 1, still crawl linearly after eight steps,
 * and their compensated |p| may read 0 all the same), then where |p| is smallest. The certified sign then
 * decides at an accurate point. Runs only in this rare case. */
static double polish_multiple(const double (*chain)[IG_MAX_DEGREE + 1], int n, double x, double l, double r)
{
    double best = x, bv;
    int best_zero = ig_sign_certified(chain[0], n, x, &bv) == 0, best_conv = 0;
    bv = fabs(bv);
    for (int j = 1; j <= 5 && j < n && !(best_zero && best_conv); ++j) { /* both: nothing better to find */
        const double *f = chain[j];
        int deg = n - j, conv = 0;
        double y = x;
        for (int it = 0; it < 8; ++it) {
            double v, dv;
            ig_horner2(f, deg, y, &v, &dv);
            double yn = y - v / dv;
            if (v == 0.0 || yn == y || fabs(yn - y) <= 4.0 * IG_U * fabs(yn)) {
                conv = 1; /* Newton settled: y is a simple root of p^(j), as accurate as it gets */
                if (v != 0.0 && yn > l && yn < r)
                    y = yn;
                break;
            }
            if (!(yn > l && yn < r))
                break;
            y = yn;
        }
        double vy;
        int zero = ig_sign_certified(chain[0], n, y, &vy) == 0;
        vy = fabs(vy);
        /* p zero within rounding beats not; then a settled Newton beats one still crawling linearly (its
         * |p| may read 0 as well, rounding hides how far off it is); then the smaller |p| */
        int better = zero != best_zero ? zero : conv != best_conv ? conv : vy < bv;
        if (better) {
            bv = vy;
            best = y;
            best_zero = zero;
            best_conv = conv;
        }
    }
    return best;
}

/* Roots of q (degree m) on [a, b] given its critical points crit[] (ascending, inside (a, b)): q is
 * monotonic between consecutive points. final != 0: q is the polynomial itself -- refine to full accuracy,
 * decide zeros with the certified sign (after polishing the critical point on dq = q' when q is small
 * there) and report roots at a and b. Otherwise only roots strictly inside (a, b) matter, as cut points for
 * the next level: a plain sign and a looser tolerance are enough (missing an even-multiplicity root of an
 * intermediate derivative leaves the next polynomial monotonic across it). out[] needs nc + 2 entries. */
static int monotone_level(const double (*chain)[IG_MAX_DEGREE + 1], int j, int n, double a, double b, const double *crit,
                          int nc, int final, double *out)
{
    const double *q = chain[j], *ddq = chain[j + 2];
    const int m = n - j;
    double xs[IG_MAX_DEGREE + 2], v[IG_MAX_DEGREE + 2], rv[IG_MAX_DEGREE + 2];
    int s[IG_MAX_DEGREE + 2];
    int np = 0;
    xs[np++] = a;
    for (int i = 0; i < nc; ++i)
        if (crit[i] > xs[np - 1] && crit[i] < b)
            xs[np++] = crit[i];
    if (b > a)
        xs[np++] = b;
    /* one a-priori rounding bound for the whole interval: gamma_2m sum |q_k| max(|a|,|b|)^k */
    double big = 0.0, g2m = 2.0 * m * IG_U;
    g2m = g2m / (1.0 - g2m);
    if (final) {
        double M = fmax(fabs(a), fabs(b));
        for (int k = m; k >= 0; --k)
            big = big * M + fabs(q[k]);
        big *= g2m;
    }
    for (int i = 0; i < np; ++i) {
        v[i] = horner(q, m, xs[i]);
        s[i] = (v[i] > 0.0) - (v[i] < 0.0);
        rv[i] = xs[i];
        if (final && !(fabs(v[i]) > big)) {
            /* the coarse bound could not decide: the bound at this very point, then the compensated value */
            double sum = 0.0, ax = fabs(xs[i]), vc;
            for (int k = m; k >= 0; --k)
                sum = sum * ax + fabs(q[k]);
            if (fabs(v[i]) > g2m * sum)
                continue;
            s[i] = ig_sign_certified(q, m, xs[i], &vc);
            v[i] = vc; /* the plain value may even have the wrong sign: refine must see the right one */
            if (s[i] != 0 && i > 0 && i < np - 1) {
                /* maybe a multiple root the critical point missed by rounding: polish, and take it only if p
                 * is then certified zero (a tiny extremum that is not a root stays as it was) */
                double y = polish_multiple(chain, n, xs[i], xs[i - 1], xs[i + 1]), vy;
                if (ig_sign_certified(q, m, y, &vy) == 0) {
                    s[i] = 0;
                    rv[i] = y;
                }
            }
        }
    }
    double tol = final ? 2.0 * IG_U : 1e-7;
    /* brackets to refine, all at once (ig_refine_many); slot[] is where each root goes in out[] */
    double bl[IG_MAX_DEGREE + 1], br[IG_MAX_DEGREE + 1], bvl[IG_MAX_DEGREE + 1], bvr[IG_MAX_DEGREE + 1];
    double bx0[IG_MAX_DEGREE + 1], broot[IG_MAX_DEGREE + 1];
    int slot[IG_MAX_DEGREE + 1], nb = 0;
    int cnt = 0;
    for (int i = 0; i < np; ++i) {
        if (s[i] == 0 && (final || (i > 0 && i < np - 1)))
            out[cnt++] = rv[i];
        if (i + 1 < np && s[i] * s[i + 1] < 0) {
            /* Start guess from the quadratic Taylor model at the critical end with the smaller |q| (q' = 0
             * there): q(xc) + q''(xc) (x - xc)^2 / 2 = 0. Near a tangent -- two roots either side of a
             * shallow extremum -- Newton would otherwise converge only linearly towards them. */
            int e = fabs(v[i]) <= fabs(v[i + 1]) ? i : i + 1;
            if (e == 0 || e == np - 1)
                e = (e == 0 && np > 2 && i + 1 < np - 1) ? i + 1 : (e == np - 1 && i > 0 ? i : -1);
            double x0 = NAN;
            if (e >= 0) {
                double dd = horner(ddq, m - 2, xs[e]) * ((double)m * (m - 1));
                double t = -2.0 * v[e] / dd;
                if (t > 0.0)
                    x0 = xs[e] + (e == i ? 1.0 : -1.0) * sqrt(t);
            }
            bl[nb] = xs[i];
            br[nb] = xs[i + 1];
            bvl[nb] = v[i];
            bvr[nb] = v[i + 1];
            bx0[nb] = x0;
            slot[nb++] = cnt++;
        }
    }
    if (nb > 0) {
        ig_refine_many(q, m, nb, bl, br, bvl, bvr, tol, bx0, broot);
        for (int i = 0; i < nb; ++i)
            out[slot[i]] = broot[i];
    }
    return cnt;
}

int ig_bracket_interval(const double *p, int n, double a, double b, double *out)
{
    /* chain[j] = p^(j) scaled to keep the leading coefficient of p: degree n - j, so p^(j) =
     * n (n-1) ... (n-j+1) chain[j] */
    double chain[IG_MAX_DEGREE][IG_MAX_DEGREE + 1];
    memcpy(chain[0], p, (size_t)(n + 1) * sizeof(double));
    for (int j = 1; j <= n - 1; ++j) {
        int m = n - j + 1; /* degree of chain[j - 1] */
        double inv = 1.0 / m;
        for (int k = 0; k < m; ++k)
            chain[j][k] = chain[j - 1][k + 1] * ((k + 1) * inv);
    }
    double buf[2][IG_MAX_DEGREE + 2];
    int cur = 0, nc = 0;
    {
        double q[2];
        const double *c2 = chain[n - 2];
        int k = ig_quadratic(c2[0], c2[1], c2[2], q);
        for (int i = 0; i < k; ++i)
            if (q[i] > a && q[i] < b)
                buf[cur][nc++] = q[i];
    }
    for (int j = n - 3; j >= 0; --j) {
        nc = monotone_level((const double (*)[IG_MAX_DEGREE + 1])chain, j, n, a, b, buf[cur], nc, j == 0, buf[1 - cur]);
        cur = 1 - cur;
    }
    memcpy(out, buf[cur], (size_t)nc * sizeof(double));
    return nc;
}

/* ---------------------------------------------------------------- interval handling */

typedef int (*interval_solver)(const double *p, int n, double a, double b, double *out);

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

/* first != 0 may swap in a first-root solver (first_solver) where the interval is solved in one piece. */
static int solve_general(const double *p, int n, double lo, double hi, interval_solver solver,
                         interval_solver first_solver, double *out)
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
    double big = fmax(fabs(a), fabs(b));
    /* coefficients are at most ~2^200 (see ig_real_roots_any); |x|^n below 2^524 keeps Horner and the
     * splitting of Dekker's product (another 2^27) far from overflow */
    if (big <= 0x1p20 || (double)n * ilogb(big) < 500.0) /* n <= 24: 2^20 is always safe */
        return (first_solver ? first_solver : solver)(p, n, a, b, out);

    /* |x| > 1 on the reversed polynomial q(y) = y^n p(1/y), y = 1/x in [-1, 1] */
    double q[IG_MAX_DEGREE + 1], tmp[IG_ROOT_BUF];
    for (int k = 0; k <= n; ++k)
        q[k] = p[n - k];
    int cnt = 0;
    if (a <= 1.0 && b >= -1.0)
        cnt = solver(p, n, fmax(a, -1.0), fmin(b, 1.0), out);
    if (b > 1.0) {
        double xa = fmax(a, 1.0);
        int k = solver(q, n, 1.0 / b, 1.0 / xa, tmp);
        for (int i = 0; i < k; ++i) {
            double x = 1.0 / tmp[i];
            if (x >= a && x <= b && !(x == 1.0 && a <= 1.0))
                out[cnt++] = x;
        }
    }
    if (a < -1.0) {
        double xb = fmin(b, -1.0);
        int k = solver(q, n, 1.0 / xb, 1.0 / a, tmp);
        for (int i = 0; i < k; ++i) {
            double x = 1.0 / tmp[i];
            if (x >= a && x <= b && !(x == -1.0 && b >= -1.0))
                out[cnt++] = x;
        }
    }
    return ig_sort_unique(out, cnt);
}

/* Which method `auto` uses per degree (after deflating zero roots); the solver report (`implgen bench
 * solvers`, README) is where this choice comes from. */
static int auto_method(int n)
{
    (void)n;
    return IG_ROOTS_BERNSTEIN;
}

static int solve_reduced(const double *p, int n, double lo, double hi, int method, int first, double *out)
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
        method = auto_method(n);
    switch (method) {
    case IG_ROOTS_CLOSED:
    case IG_ROOTS_CLOSED_PLAIN: {
        int polish = method == IG_ROOTS_CLOSED;
        if (n == 3)
            return ig_closed_cubic(p, lo, hi, polish, out);
        if (n == 4)
            return ig_closed_quartic(p, lo, hi, polish, out);
        return solve_general(p, n, lo, hi, ig_bracket_interval, NULL, out);
    }
    case IG_ROOTS_STURM:
        return solve_general(p, n, lo, hi, ig_sturm_interval, NULL, out);
    case IG_ROOTS_BRACKET:
        return solve_general(p, n, lo, hi, ig_bracket_interval, NULL, out);
    case IG_ROOTS_BERNSTEIN:
        return solve_general(p, n, lo, hi, ig_bernstein_interval, first ? ig_bernstein_first : NULL, out);
    default:
        return 0;
    }
}

int ig_roots_core(const double *c, int n, double lo, double hi, int method, int first, double *roots)
{
    if (!c || !roots || n < 0 || n > IG_MAX_DEGREE)
        return 0;
    if (!(lo <= hi)) /* also NaN bounds */
        return 0;
    if (n == 1) { /* a plane, the common case in a scene (the tracer's ground): no set-up, no scaling needed
                   * (the quotient is scale-free); c[0] == 0 gives +0, c[1] == 0 no root */
        double x = -c[0] / c[1];
        if (!(fabs(c[0]) <= DBL_MAX) || !(fabs(c[1]) <= DBL_MAX) || !isfinite(x) || !(x >= lo && x <= hi))
            return 0; /* also c[1] == 0: no root, or the zero polynomial */
        roots[0] = x == 0.0 ? 0.0 : x;
        return 1;
    }
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
        k = solve_reduced(p + m, deg, lo, hi, method, first, r);
    if (m > 0)
        r[k++] = 0.0;
    if (k > 1)
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
