/* Derivative bracketing (in the spirit of Yuksel 2022): the roots of p^(n-2) (a quadratic) cut [lo, hi]
 * into pieces where p^(n-3) is monotonic; each sign change there is one root, found by the refinement
 * (roots_refine.c); those roots cut the interval for p^(n-4), and so on up to p. A piece end where p is zero
 * within rounding (certified by a compensated evaluation) is reported as a root: that is how a tangent (even
 * multiplicity) root, which has no sign change, is found, and why a tiny positive minimum is not.
 *
 * First-root mode (ig_bracket_first) runs the same levels and stops the last one at its first root, with the
 * same helpers on the same inputs, so the root is bitwise the first of ig_bracket_interval's list.
 */
#include "roots_impl.h"

#include <math.h>
#include <string.h>

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

/* The rounding bound of a level: gamma_2m, and at the final level one a-priori bound for the whole interval,
 * gamma_2m sum |q_k| max(|a|,|b|)^k. */
static inline void level_bounds(const double *q, int m, double a, double b, int final, double *big, double *g2m)
{
    double g = 2.0 * m * IG_U;
    *g2m = g / (1.0 - g);
    *big = final ? ig_horner_abs(q, m, ig_max(fabs(a), fabs(b))) * *g2m : 0.0;
}

/* q at a point x of the level: value and sign; at the final level, where the coarse bound cannot decide, the
 * bound at this very point, then the compensated value (the plain one may even have the wrong sign: refine
 * must see the right one). *unsure: the certified sign was needed (a candidate for polish_multiple). */
static inline void level_point(const double *q, int m, double x, int final, double big, double g2m, double *v, int *s,
                               int *unsure)
{
    *v = ig_horner(q, m, x);
    *s = (*v > 0.0) - (*v < 0.0);
    *unsure = 0;
    if (final && !(fabs(*v) > big)) {
        double sum = ig_horner_abs(q, m, fabs(x)), vc;
        if (fabs(*v) > g2m * sum)
            return;
        *s = ig_sign_certified(q, m, x, &vc);
        *v = vc;
        *unsure = 1;
    }
}

/* An interior point of the final level whose sign needed certifying and is not zero: maybe a multiple root the
 * critical point missed by rounding. Polish, and take it only if p is then certified zero (a tiny extremum that
 * is not a root stays as it was). */
static void level_polish(const double (*chain)[IG_MAX_DEGREE + 1], int n, const double *xs, int i, int *s, double *rv)
{
    double y = polish_multiple(chain, n, xs[i], xs[i - 1], xs[i + 1]), vy;
    if (ig_sign_certified(chain[0], n, y, &vy) == 0) {
        *s = 0;
        *rv = y;
    }
}

/* Start guess for the bracket [xs[i], xs[i+1]] of a level (last: the index of the last point, or any number
 * above i + 1 while that is not known): the quadratic Taylor model at the critical end with the smaller |q|
 * (q' = 0 there), q(xc) + q''(xc) (x - xc)^2 / 2 = 0. Near a tangent -- two roots either side of a shallow
 * extremum -- Newton would otherwise converge only linearly towards them. */
static inline double level_guess(const double *ddq, int m, const double *xs, const double *v, int i, int last)
{
    int e = fabs(v[i]) <= fabs(v[i + 1]) ? i : i + 1;
    if (e == 0 || e == last)
        e = (e == 0 && last > 1 && i + 1 < last) ? i + 1 : (e == last && i > 0 ? i : -1);
    double x0 = NAN;
    if (e >= 0) {
        double dd = ig_horner(ddq, m - 2, xs[e]) * ((double)m * (m - 1));
        double t = -2.0 * v[e] / dd;
        if (t > 0.0)
            x0 = xs[e] + (e == i ? 1.0 : -1.0) * sqrt(t);
    }
    return x0;
}

/* One level of the chain: p^(j) at the points a, its critical points inside (a, b), and b; each point's value,
 * sign, whether the sign is unsure, and where a polish moved it. */
typedef struct {
    const double (*chain)[IG_MAX_DEGREE + 1];
    const double *q, *ddq; /* p^(j) and p^(j+2), scaled */
    int n, m, np, final;
    double big, g2m, tol;
    double xs[IG_MAX_DEGREE + 2], v[IG_MAX_DEGREE + 2], rv[IG_MAX_DEGREE + 2];
    int s[IG_MAX_DEGREE + 2], unsure[IG_MAX_DEGREE + 2];
} level;

static void level_init(level *L, const double (*chain)[IG_MAX_DEGREE + 1], int j, int n, double a, double b,
                       const double *crit, int nc, int final)
{
    L->chain = chain;
    L->q = chain[j];
    L->ddq = chain[j + 2];
    L->n = n;
    L->m = n - j;
    L->final = final;
    L->np = 0;
    L->xs[L->np++] = a;
    for (int i = 0; i < nc; ++i)
        if (crit[i] > L->xs[L->np - 1] && crit[i] < b)
            L->xs[L->np++] = crit[i];
    if (b > a)
        L->xs[L->np++] = b;
    level_bounds(L->q, L->m, a, b, final, &L->big, &L->g2m);
    L->tol = final ? 2.0 * IG_U : 1e-7;
}

/* Point i evaluated; an unsure sign polished when it is not an end. */
static void level_eval(level *L, int i)
{
    level_point(L->q, L->m, L->xs[i], L->final, L->big, L->g2m, &L->v[i], &L->s[i], &L->unsure[i]);
    L->rv[i] = L->xs[i];
}

static void level_settle(level *L, int i)
{
    if (L->unsure[i] && L->s[i] != 0 && i > 0 && i < L->np - 1) {
        level_polish(L->chain, L->n, L->xs, i, &L->s[i], &L->rv[i]);
        L->unsure[i] = 0;
    }
}

/* Whether point i's zero is a root of this level (an end's zero counts only at the final level). */
static int level_zero(const level *L, int i) { return L->s[i] == 0 && (L->final || (i > 0 && i < L->np - 1)); }

/* The first root only: points evaluated (and polished) left to right as far as the first root needs; the point
 * after a bracket too, since a polish reads both neighbours of a point. */
static int level_first(level *L, double *out)
{
    int known = 0;
    for (int i = 0; i < L->np; ++i) {
        for (; known < L->np && known <= i + 1; ++known)
            level_eval(L, known);
        for (int k = i; k <= i + 1 && k < L->np; ++k)
            level_settle(L, k);
        if (level_zero(L, i)) {
            /* a polished zero may lie anywhere between its neighbours, so the next point's, when it is a
             * zero too, can be the smaller one (two critical points at a triple root); no later one can */
            int next = i + 1 < L->np && level_zero(L, i + 1) && L->rv[i + 1] < L->rv[i];
            out[0] = next ? L->rv[i + 1] : L->rv[i];
            return 1;
        }
        if (i + 1 < L->np && L->s[i] * L->s[i + 1] < 0) { /* ig_refine_many is ig_refine lane by lane */
            out[0] = ig_refine(L->q, L->m, L->xs[i], L->xs[i + 1], L->v[i], L->v[i + 1], L->tol,
                               level_guess(L->ddq, L->m, L->xs, L->v, i, L->np - 1));
            return 1;
        }
    }
    return 0;
}

/* Every root: every point evaluated, then the brackets refined all at once (ig_refine_many); slot[] is where
 * each root goes in out[]. */
static int level_all(level *L, double *out)
{
    double bl[IG_MAX_DEGREE + 1], br[IG_MAX_DEGREE + 1], bvl[IG_MAX_DEGREE + 1], bvr[IG_MAX_DEGREE + 1];
    double bx0[IG_MAX_DEGREE + 1], broot[IG_MAX_DEGREE + 1];
    int slot[IG_MAX_DEGREE + 1], nb = 0, cnt = 0;
    for (int i = 0; i < L->np; ++i) {
        level_eval(L, i);
        level_settle(L, i);
    }
    for (int i = 0; i < L->np; ++i) {
        if (level_zero(L, i))
            out[cnt++] = L->rv[i];
        if (i + 1 < L->np && L->s[i] * L->s[i + 1] < 0) {
            bl[nb] = L->xs[i];
            br[nb] = L->xs[i + 1];
            bvl[nb] = L->v[i];
            bvr[nb] = L->v[i + 1];
            bx0[nb] = level_guess(L->ddq, L->m, L->xs, L->v, i, L->np - 1);
            slot[nb++] = cnt++;
        }
    }
    if (nb > 0) {
        ig_refine_many(L->q, L->m, nb, bl, br, bvl, bvr, L->tol, bx0, broot);
        for (int i = 0; i < nb; ++i)
            out[slot[i]] = broot[i];
    }
    return cnt;
}

/* Roots of q (degree m) on [a, b] given its critical points crit[] (ascending, inside (a, b)): q is
 * monotonic between consecutive points. final != 0: q is the polynomial itself -- refine to full accuracy,
 * decide zeros with the certified sign (after polishing the critical point on dq = q' when q is small
 * there) and report roots at a and b. Otherwise only roots strictly inside (a, b) matter, as cut points for
 * the next level: a plain sign and a looser tolerance are enough (missing an even-multiplicity root of an
 * intermediate derivative leaves the next polynomial monotonic across it). out[] needs nc + 2 entries. */
static int monotone_level(const double (*chain)[IG_MAX_DEGREE + 1], int j, int n, double a, double b,
                          const double *crit, int nc, int final, int first, double *out)
{
    level L;
    level_init(&L, chain, j, n, a, b, crit, nc, final);
    return first ? level_first(&L, out) : level_all(&L, out);
}

/* chain[j] = p^(j) scaled to keep the leading coefficient of p: degree n - j, so p^(j) = n (n-1) ... (n-j+1)
 * chain[j]; and the roots of chain[n - 2] (a quadratic) inside (a, b), ascending, into q2 (returns how many). */
static int derivative_chain(const double *p, int n, double a, double b, double (*chain)[IG_MAX_DEGREE + 1], double *q2)
{
    memcpy(chain[0], p, (size_t)(n + 1) * sizeof(double));
    for (int j = 1; j <= n - 1; ++j) {
        int m = n - j + 1; /* degree of chain[j - 1] */
        double inv = 1.0 / m;
        for (int k = 0; k < m; ++k)
            chain[j][k] = chain[j - 1][k + 1] * ((k + 1) * inv);
    }
    double q[2];
    const double *c2 = chain[n - 2];
    int k = ig_quadratic(c2[0], c2[1], c2[2], q), nc = 0;
    for (int i = 0; i < k; ++i)
        if (q[i] > a && q[i] < b)
            q2[nc++] = q[i];
    return nc;
}

int ig_bracket_roots(const double *p, int n, double a, double b, int first, double *out)
{
    double chain[IG_MAX_DEGREE][IG_MAX_DEGREE + 1];
    double buf[2][IG_MAX_DEGREE + 2];
    int cur = 0, nc = derivative_chain(p, n, a, b, chain, buf[0]);
    for (int j = n - 3; j >= 0; --j) {
        nc = monotone_level((const double(*)[IG_MAX_DEGREE + 1]) chain, j, n, a, b, buf[cur], nc, j == 0,
                            first && j == 0, buf[1 - cur]);
        cur = 1 - cur;
    }
    memcpy(out, buf[cur], (size_t)nc * sizeof(double));
    return nc;
}

int ig_bracket_interval(const double *p, int n, double a, double b, double *out)
{
    return ig_bracket_roots(p, n, a, b, 0, out);
}

int ig_bracket_first(const double *p, int n, double a, double b, double *out)
{
    return ig_bracket_roots(p, n, a, b, 1, out);
}
