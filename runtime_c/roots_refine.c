/* Refinement of a bracketed root (ig_refine) and of several brackets of one polynomial at once
 * (ig_refine_many): Householder's third-order step on a simple root, with bisection and, for anything
 * unusual, an rtsafe-style safeguarded Newton behind it; brackets of one polynomial are refined four at a
 * time, so that their evaluation chains overlap. Shared by the sturm, bracket and bernstein methods.
 */
#include "roots_impl.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

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
            if (newton_before && as <= 1e-3 * fabs(dx) && as <= 1e-3 * fabs(xn) &&
                (as / dx) * (as / dx) * as <= tol * fabs(xn))
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
    /* v (d^2 - v hdd) / (d^3 - 2 v d hdd + v^2 h3), written with the Newton step nw = v / d so that nothing
     * underflows where p and its derivatives are tiny (a root at 1e-152 of a polynomial scaled to 1) */
    double nw = v / d, a = nw * (hdd / d);
    double step = nw * (1.0 - a) / (1.0 - 2.0 * a + nw * (nw * (h3 / d))), xn = x - step;
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

void ig_refine_many(const double *c, int n, int k, const double *l, const double *r, const double *vl, const double *vr,
                    double tol, const double *x0, double *roots)
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
