/* Derivative bracketing (in the spirit of Yuksel 2022): the roots of p^(n-2) (a quadratic) cut [lo, hi]
 * into pieces where p^(n-3) is monotonic; each sign change there is one root, found by the refinement
 * (roots_refine.c); those roots cut the interval for p^(n-4), and so on up to p. A piece end where p is zero
 * within rounding (certified by a compensated evaluation) is reported as a root: that is how a tangent (even
 * multiplicity) root, which has no sign change, is found, and why a tiny positive minimum is not.
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

/* Roots of q (degree m) on [a, b] given its critical points crit[] (ascending, inside (a, b)): q is
 * monotonic between consecutive points. final != 0: q is the polynomial itself -- refine to full accuracy,
 * decide zeros with the certified sign (after polishing the critical point on dq = q' when q is small
 * there) and report roots at a and b. Otherwise only roots strictly inside (a, b) matter, as cut points for
 * the next level: a plain sign and a looser tolerance are enough (missing an even-multiplicity root of an
 * intermediate derivative leaves the next polynomial monotonic across it). out[] needs nc + 2 entries. */
static int monotone_level(const double (*chain)[IG_MAX_DEGREE + 1], int j, int n, double a, double b,
                          const double *crit, int nc, int final, double *out)
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
        big = ig_horner_abs(q, m, ig_max(fabs(a), fabs(b))) * g2m;
    }
    for (int i = 0; i < np; ++i) {
        v[i] = ig_horner(q, m, xs[i]);
        s[i] = (v[i] > 0.0) - (v[i] < 0.0);
        rv[i] = xs[i];
        if (final && !(fabs(v[i]) > big)) {
            /* the coarse bound could not decide: the bound at this very point, then the compensated value */
            double sum = ig_horner_abs(q, m, fabs(xs[i])), vc;
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
                double dd = ig_horner(ddq, m - 2, xs[e]) * ((double)m * (m - 1));
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
        nc = monotone_level((const double(*)[IG_MAX_DEGREE + 1]) chain, j, n, a, b, buf[cur], nc, j == 0, buf[1 - cur]);
        cur = 1 - cur;
    }
    memcpy(out, buf[cur], (size_t)nc * sizeof(double));
    return nc;
}
