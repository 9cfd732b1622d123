/* Root isolation by subdivision in the Bernstein basis, refinement on the power form.
 *
 * On [a, b] the polynomial is rewritten as q(s) = p(a + s h), h = b - a, s in [0, 1], and q in the
 * Bernstein basis of degree n: q(s) = sum_i b_i C(n,i) s^i (1-s)^(n-i). The number of sign changes of
 * b_0 .. b_n bounds the number of roots in (0, 1) from above and has the same parity (Descartes' rule for
 * the Bernstein basis), so
 *   - no sign change: no root on the piece;
 *   - one sign change: exactly one root, a simple one, and b_0 = q(0), b_n = q(1) bracket it: it is refined
 *     by the same safeguarded Newton on the ORIGINAL coefficients the bracketing method uses, so the root is
 *     as accurate as bracketing's;
 *   - more: the piece is halved (de Casteljau at s = 1/2, exact weights) and both halves examined, left first.
 * Splitting the control polygon converges to the curve quadratically, so well separated roots are isolated
 * after a few halvings. In first-root mode the leftmost piece that holds a root ends the search, which is
 * what a ray needs: the nearest hit, not all of them.
 *
 * Rounding: every b_i carries an error below tol = 24 n u M, M = sum |p_k| (|a| + |h|)^k (a priori bound of
 * the Taylor shift, the basis change and up to BZ_MAX_DEPTH halvings). A coefficient within tol of zero has no
 * certain sign. At the piece ends, where b_0 = p(t_l) and b_n = p(t_r), the compensated evaluation of
 * ig_sign_certified decides instead; inside, uncertain coefficients that might hide sign changes (see
 * variations()) force a split.
 *
 * Whenever this cannot conclude -- a piece still ambiguous after BZ_MAX_DEPTH halvings (a tangent or nearly
 * tangent ray, a cluster of roots), or p zero within rounding at a piece end -- the derivative-bracketing
 * solver runs on the whole interval and its answer is returned unchanged: in the doubtful cases the two methods
 * give identical results by construction, and bracketing is the one that reports tangent roots.
 */
#include "roots_impl.h"

#include <math.h>
#include <string.h>

#define BZ_MAX_DEPTH 16

typedef struct {
    const double *p; /* power-form coefficients, exact degree n */
    int n;
    double a, b, h; /* the interval; t = a + s h */
    double tol;     /* |b_i| <= tol: the sign of b_i is not certain */
    int first;      /* stop at the leftmost root */
    double *out;
    int cnt;
    int fallback; /* something was not certain: bracketing decides */
} bz_ctx;

/* Bernstein coefficients of p(a + s h) on s in [0, 1]. */
static void to_bernstein(const double *p, int n, double a, double h, double *b)
{
    double t[IG_MAX_DEGREE + 1];
    memcpy(t, p, (size_t)(n + 1) * sizeof(double));
    for (int i = 0; i < n; ++i) /* Taylor shift: t(y) = p(a + y), repeated synthetic division */
        for (int k = n - 1; k >= i; --k)
            t[k] += a * t[k + 1];
    double hp = 1.0, binom = 1.0; /* h^j, C(n, j): exact integers up to C(24, 12) */
    for (int j = 0; j <= n; ++j) {
        b[j] = t[j] * hp / binom;
        hp *= h;
        binom = binom * (n - j) / (j + 1);
    }
    for (int r = 1; r <= n; ++r) /* b_i = sum_j C(i, j) w_j: Pascal's triangle, additions only */
        for (int i = n; i >= r; --i)
            b[i] += b[i - 1];
}

/* de Casteljau at s = 1/2: the halves' coefficients (weights 1/2: the only rounding is in the sums). */
static void split_half(const double *b, int n, double *L, double *R)
{
    double w[IG_MAX_DEGREE + 1];
    memcpy(w, b, (size_t)(n + 1) * sizeof(double));
    L[0] = w[0];
    R[n] = w[n];
    for (int r = 1; r <= n; ++r) {
        for (int i = 0; i <= n - r; ++i)
            w[i] = 0.5 * (w[i] + w[i + 1]);
        L[r] = w[0];
        R[n - r] = w[n - r];
    }
}

/* Sign changes of b[0..n] with end signs sl, sr (certain, nonzero); -1 when uncertain interior coefficients
 * could hide changes: a run of them between two equal signs (+ ? + may be + - +), or a run of two or more
 * between opposite signs (+ ? ? - may be + - + -). A single one between opposite signs changes nothing. */
static int variations(const double *b, int n, double tol, int sl, int sr)
{
    int v = 0, last = sl, pending = 0;
    for (int i = 1; i <= n; ++i) {
        int s;
        if (i == n) {
            s = sr;
        } else if (!(fabs(b[i]) > tol)) {
            ++pending;
            continue;
        } else {
            s = b[i] > 0.0 ? 1 : -1;
        }
        if (pending > 1 || (pending == 1 && s == last))
            return -1;
        if (s != last) {
            ++v;
            last = s;
        }
        pending = 0;
    }
    return v;
}

/* Certain sign of p at t given the Bernstein value bv there (b_0 or b_n of a piece): the plain value when it
 * is clear of the rounding band, else the compensated evaluation (0: p is zero within rounding). */
static int end_sign(const bz_ctx *c, double bv, double t, double *val)
{
    if (fabs(bv) > c->tol) {
        *val = bv;
        return bv > 0.0 ? 1 : -1;
    }
    return ig_sign_certified(c->p, c->n, t, val);
}

/* Start guess for the one root of a piece: where the control polygon first crosses zero (the polygon lies
 * within O(h^2) of the curve, so this is close); NaN (false position) when no segment crosses. */
static double polygon_crossing(const double *b, int n, double tl, double tr)
{
    for (int i = 0; i < n; ++i)
        if ((b[i] > 0.0) != (b[i + 1] > 0.0) && b[i] != b[i + 1]) {
            double s = (i + b[i] / (b[i] - b[i + 1])) / n;
            return tl + s * (tr - tl);
        }
    return NAN;
}

/* Piece [s0, s1] of [0, 1] with Bernstein coefficients b, end signs sl, sr and values vl, vr of p there. */
static void piece(bz_ctx *c, const double *b, double s0, double s1, double tl, double tr, int sl, int sr,
                  double vl, double vr, int depth)
{
    if (c->fallback || (c->first && c->cnt > 0))
        return;
    int v = variations(b, c->n, c->tol, sl, sr);
    if (v == 0)
        return;
    if (v == 1) {
        c->out[c->cnt++] = ig_refine(c->p, c->n, tl, tr, vl, vr, 2.0 * IG_U, polygon_crossing(b, c->n, tl, tr));
        return;
    }
    double sm = 0.5 * (s0 + s1);
    double tm = c->a + sm * c->h;
    if (depth >= BZ_MAX_DEPTH || !(tm > tl && tm < tr)) {
        c->fallback = 1;
        return;
    }
    double L[IG_MAX_DEGREE + 1], R[IG_MAX_DEGREE + 1], vm;
    split_half(b, c->n, L, R);
    int sm_sign = end_sign(c, L[c->n], tm, &vm);
    if (sm_sign == 0) { /* p zero within rounding at the split point */
        c->fallback = 1;
        return;
    }
    piece(c, L, s0, sm, tl, tm, sl, sm_sign, vl, vm, depth + 1);
    piece(c, R, sm, s1, tm, tr, sm_sign, sr, vm, vr, depth + 1);
}

static int bernstein(const double *p, int n, double a, double b, int first, double *out)
{
    double h = b - a;
    if (!(h > 0.0) || !isfinite(h))
        return ig_bracket_interval(p, n, a, b, out);
    bz_ctx c = {p, n, a, b, h, 0.0, first, out, 0, 0};
    double x = fabs(a) + h, M = 0.0;
    for (int k = n; k >= 0; --k)
        M = M * x + fabs(p[k]);
    c.tol = 24.0 * n * IG_U * M;
    if (!isfinite(c.tol))
        return ig_bracket_interval(p, n, a, b, out);
    double bz[IG_MAX_DEGREE + 1], vl, vr;
    to_bernstein(p, n, a, h, bz);
    int sl = end_sign(&c, bz[0], a, &vl), sr = end_sign(&c, bz[n], b, &vr);
    if (sl == 0 || sr == 0) /* a root at an end of the interval (within rounding) */
        return ig_bracket_interval(p, n, a, b, out);
    piece(&c, bz, 0.0, 1.0, a, b, sl, sr, vl, vr, 0);
    if (c.fallback)
        return ig_bracket_interval(p, n, a, b, out);
    return c.cnt;
}

int ig_bernstein_interval(const double *p, int n, double a, double b, double *out)
{
    return bernstein(p, n, a, b, 0, out);
}

int ig_bernstein_first(const double *p, int n, double a, double b, double *out)
{
    return bernstein(p, n, a, b, 1, out);
}
