/* Root isolation by subdivision in the Bernstein basis, refinement on the power form.
 *
 * On [a, b] the polynomial is rewritten as q(s) = p(a + s h), h = b - a, s in [0, 1], and q in the
 * Bernstein basis of degree n: q(s) = sum_i b_i C(n,i) s^i (1-s)^(n-i). The number of sign changes of
 * b_0 .. b_n bounds the number of roots in (0, 1) from above and has the same parity (Descartes' rule for
 * the Bernstein basis), so
 *   - no sign change: no root on the piece;
 *   - one sign change: exactly one root, a simple one, and b_0 = q(0), b_n = q(1) bracket it: it is refined
 *     by the same ig_refine on the ORIGINAL coefficients the bracketing method uses, so the root is as
 *     accurate as bracketing's. All-roots mode collects the brackets and refines them together at the end
 *     (ig_refine_many: their evaluations overlap), first-root mode refines the first one at once;
 *   - more: the piece is halved (de Casteljau at s = 1/2, exact weights) and both halves examined, left first.
 * Splitting the control polygon converges to the curve quadratically, so well separated roots are isolated
 * after a few halvings. In first-root mode the leftmost piece that holds a root ends the search, which is
 * what a ray needs: the nearest hit, not all of them.
 *
 * Rounding: [a, b] is converted through one Taylor shift to its midpoint m, both halves from it, so every b_i
 * is within tol = 7 n u M of the exact one, M = sum |p_k| max(|a|, |b|)^k: the scale of p on the interval (a
 * shift to an end would make it sum |p_k| (|a| + |b - a|)^k, which at degree 20 on [-1, 1] is 3^20 times more).
 * Each halving adds (n + 1) u max |b_i| to a piece's tol. A coefficient within tol of zero has no certain sign.
 * At the piece ends, where b_0 = p(t_l) and b_n = p(t_r), the compensated evaluation of ig_sign_certified
 * decides instead; inside, uncertain coefficients that might hide sign changes (see variations()) force a
 * split. A piece with uncertain coefficients is first converted afresh from the power form at its own scale,
 * sum |p_k| max(|t_l|, |t_r|)^k, when that is at least four times below its inherited tol (near the point the
 * ray polynomial is expanded at, p can be tiny everywhere).
 *
 * Whatever this cannot decide -- a piece still ambiguous after BZ_MAX_DEPTH halvings (a tangent or nearly
 * tangent ray, a cluster of roots), or p zero within rounding at a split point -- goes, that piece alone, to
 * the derivative-bracketing solver (the one that reports tangent roots). Pieces are visited left to right in
 * both modes and each undecided piece is bracketed the same way, so the first root in first-root mode is
 * bitwise the first root of the full search.
 *
 * `auto` (roots.c) uses this method except on the whole line at degree <= 8 when every root may be real
 * (Newton's inequalities hold): there isolating each root by halving from the root bound is what bracketing
 * does better, and multiple roots and clusters would end here after BZ_MAX_DEPTH halvings anyway.
 *
 * Speed: the body (roots_bernstein_body.h) is compiled once per degree 3 .. 12 and 14, 16, .. 24 with the
 * degree a constant, so the O(n^2) loops unroll into straight-line code, and once more for any degree.
 */
#include "roots_impl.h"

#include <math.h>
#include <string.h>

#define BZ_MAX_DEPTH 12

typedef struct {
    const double *p; /* power-form coefficients, exact degree n */
    int n;
    int first; /* stop at the leftmost root (IG_FIRST_ROOT), left unrefined with IG_ANY_ROOT */
    double *out;
    int cnt;
    /* pieces the subdivision could not decide went to bracketing: their roots, and how many pieces */
    int nfb;
    double fb[IG_MAX_DEGREE + 2];
    int *fallbacks; /* NULL, or a counter of such pieces (the solver report's statistics) */
    /* all-roots mode: the isolating brackets (ends, values there, start guess), refined together at the end */
    double bl[IG_MAX_DEGREE], br[IG_MAX_DEGREE], bvl[IG_MAX_DEGREE], bvr[IG_MAX_DEGREE], bx0[IG_MAX_DEGREE];
} bz_ctx;

/* 1/k, k = 0 .. IG_MAX_DEGREE (entry 0 unused): turns the binomial scaling into products. */
static const double bz_inv[IG_MAX_DEGREE + 1] = {0.0,      1.0,      1.0 / 2,  1.0 / 3,  1.0 / 4,  1.0 / 5,  1.0 / 6,
                                                 1.0 / 7,  1.0 / 8,  1.0 / 9,  1.0 / 10, 1.0 / 11, 1.0 / 12, 1.0 / 13,
                                                 1.0 / 14, 1.0 / 15, 1.0 / 16, 1.0 / 17, 1.0 / 18, 1.0 / 19, 1.0 / 20,
                                                 1.0 / 21, 1.0 / 22, 1.0 / 23, 1.0 / 24};

/* Certain sign of p at t given the Bernstein value bv there (b_0 or b_n of a piece, within tol of the exact
 * value): the plain value when it is clear of the rounding band, else the compensated evaluation (0: p is zero
 * within rounding). */
static int end_sign(const bz_ctx *c, double bv, double t, double tol, double *val)
{
    if (fabs(bv) > tol) {
        *val = bv;
        return bv > 0.0 ? 1 : -1;
    }
    return ig_sign_certified(c->p, c->n, t, val);
}

/* A piece [tl, tr] the subdivision cannot decide (both ends of certain, nonzero sign): bracketing finds its
 * roots, tangent ones included; the pieces left and right of it stay with the subdivision. */
static void bz_fallback(bz_ctx *c, double tl, double tr)
{
    double r[IG_ROOT_BUF];
    int k = ig_bracket_roots(c->p, c->n, tl, tr, c->first, r);
    for (int i = 0; i < k && c->nfb < IG_MAX_DEGREE + 2; ++i)
        c->fb[c->nfb++] = r[i];
    if (c->fallbacks)
        ++*c->fallbacks;
}

/* A yes/no query's answer from a piece [tl, tr] whose ends' certified signs differ, so that a root lies strictly
 * inside: its middle, when that is strictly inside (1); 0 when tl and tr are too close for one. */
static int any_inside(bz_ctx *c, double tl, double tr)
{
    double x = 0.5 * tl + 0.5 * tr;
    if (!(x > tl && x < tr))
        return 0;
    c->out[c->cnt++] = x;
    return 1;
}

/* Fully unrolled loops in the fixed-degree bodies (GCC's and Clang's pragma; other compilers ignore it) */
#if defined(__GNUC__)
#define BZ_PRAGMA(x) _Pragma(#x)
#define BZ_UNROLL BZ_PRAGMA(GCC unroll 32)
#else
#define BZ_UNROLL
#endif

#define BZ_CAT2(a, b) a##_##b
#define BZ_CAT(a, b) BZ_CAT2(a, b)

#define BZ_TAG 3
#include "roots_bernstein_body.h"
#define BZ_TAG 4
#include "roots_bernstein_body.h"
#define BZ_TAG 5
#include "roots_bernstein_body.h"
#define BZ_TAG 6
#include "roots_bernstein_body.h"
#define BZ_TAG 7
#include "roots_bernstein_body.h"
#define BZ_TAG 8
#include "roots_bernstein_body.h"
#define BZ_TAG 9
#include "roots_bernstein_body.h"
#define BZ_TAG 10
#include "roots_bernstein_body.h"
#define BZ_TAG 11
#include "roots_bernstein_body.h"
#define BZ_TAG 12
#include "roots_bernstein_body.h"
#define BZ_TAG 14
#include "roots_bernstein_body.h"
#define BZ_TAG 16
#include "roots_bernstein_body.h"
#define BZ_TAG 18
#include "roots_bernstein_body.h"
#define BZ_TAG 20
#include "roots_bernstein_body.h"
#define BZ_TAG 22
#include "roots_bernstein_body.h"
#define BZ_TAG 24
#include "roots_bernstein_body.h"
#define BZ_TAG any
#define BZ_ANY_DEGREE
#include "roots_bernstein_body.h"

typedef void (*bz_piece_fn)(bz_ctx *c, const double *b, double tl, double tr, int sl, int sr, double vl, double vr,
                            double tol, int depth);
typedef void (*bz_basis_fn)(const double *p, int n, double m, double rl, double rr, double *L, double *R);

/* The code specialised per degree: 3 to 12 and the even degrees to 24 (a closed surface's ray polynomials;
 * each specialisation is 7-15 % faster at degree 16-24 than _any, and every one adds compile time to the
 * first build of the runtime); other degrees run the _any version. */
#define BZ_SPECIAL (IG_MAX_DEGREE + 1)
#define BZ_ENTRY(d) [d] = {to_bernstein_mid_##d, piece_##d}
static const struct {
    bz_basis_fn to_bernstein;
    bz_piece_fn piece;
} bz_special[BZ_SPECIAL] = {BZ_ENTRY(3),  BZ_ENTRY(4),  BZ_ENTRY(5),  BZ_ENTRY(6),  BZ_ENTRY(7),  BZ_ENTRY(8),
                            BZ_ENTRY(9),  BZ_ENTRY(10), BZ_ENTRY(11), BZ_ENTRY(12), BZ_ENTRY(14), BZ_ENTRY(16),
                            BZ_ENTRY(18), BZ_ENTRY(20), BZ_ENTRY(22), BZ_ENTRY(24)};
#undef BZ_ENTRY

/* IG_ANY_ROOT asks only whether a root exists: where two certified signs of p differ, one does, in between. The
 * signs at a, at the middle m and at b (the conversion's end values, certified by end_sign), and p's exact value
 * p[0] at 0 when 0 lies inside (the ray polynomial is expanded about a point of the ray next to the object, often
 * inside the solid it crosses): the middle of the first pair that differs, a point strictly inside that pair's
 * interval; NaN when they all agree. */
static double any_sign_change(double p0, double a, double m, double b, int sl, int sm, int sr)
{
    int s0 = p0 > 0.0 ? 1 : (p0 < 0.0 ? -1 : 0);
    double x = NAN, l = a, r = b;
    if (sl != sm) {
        r = m;
    } else if (sm != sr) {
        l = m;
    } else if (s0 != 0 && s0 != sl && a < 0.0 && 0.0 < b && m != 0.0) {
        if (m > 0.0) /* the change is in (a, 0) */
            r = 0.0;
        else
            l = 0.0;
    } else {
        return NAN;
    }
    x = 0.5 * l + 0.5 * r;
    return x > l && x < r ? x : NAN;
}

/* [a, b] as a whole to bracketing (its first-root mode when first != 0: bitwise the first of its list). */
static int bracket_whole(const double *p, int n, double a, double b, int first, double *out)
{
    return ig_bracket_roots(p, n, a, b, first, out);
}

static int bernstein(const double *p, int n, double a, double b, int first, double *out, int *fallbacks)
{
    double m = 0.5 * a + 0.5 * b;
    if (!(m > a && m < b) || !isfinite(b - a))
        return bracket_whole(p, n, a, b, first, out);
    /* Rounding: the Taylor shift to m errs by at most gamma_2n times the same shift on |p_k| and |m|; the
     * scaling (3 roundings per power) and Pascal's additions (n levels) add gamma_4n relative to what they sum.
     * Every term is bounded by M = sum |p_k| (|m| + r)^k with r the larger half, |m| + r = max(|a|, |b|), so
     * each coefficient is within 6 n u M (with room for the second-order terms below) of the exact one. */
    double M = ig_horner_abs(p, n, ig_max(fabs(a), fabs(b)));
    double tol = 7.0 * n * IG_U * M;
    if (!isfinite(tol))
        return bracket_whole(p, n, a, b, first, out);
    bz_ctx c;
    c.p = p;
    c.n = n;
    c.first = first;
    c.out = out;
    c.cnt = 0;
    c.nfb = 0;
    c.fallbacks = fallbacks;
    double L[IG_MAX_DEGREE + 1], R[IG_MAX_DEGREE + 1], vl, vm, vr;
    bz_basis_fn to_bernstein = to_bernstein_mid_any;
    bz_piece_fn piece = piece_any;
    if (n < BZ_SPECIAL && bz_special[n].piece) {
        to_bernstein = bz_special[n].to_bernstein;
        piece = bz_special[n].piece;
    }
    to_bernstein(p, n, m, m - a, b - m, L, R);
    int sl = end_sign(&c, L[0], a, tol, &vl), sr = end_sign(&c, R[n], b, tol, &vr);
    int sm = end_sign(&c, R[0], m, tol, &vm);
    if (sl == 0 || sr == 0 || sm == 0) /* a root at an end or the middle (within rounding) */
        return bracket_whole(p, n, a, b, first, out);
    if (first == IG_ANY_ROOT) {
        double x = any_sign_change(p[0], a, m, b, sl, sm, sr);
        if (!isnan(x)) {
            out[0] = x;
            return 1;
        }
    }
    piece(&c, L, a, m, sl, sm, vl, vm, tol, 1);
    piece(&c, R, m, b, sm, sr, vm, vr, tol, 1);
    if (first) { /* the leftmost piece holding a root ended the search */
        if (c.cnt == 0 && c.nfb > 0)
            out[c.cnt++] = c.fb[0];
        return c.cnt;
    }
    if (c.cnt > 0) /* several roots in flight at once: about the time of one */
        ig_refine_many(p, n, c.cnt, c.bl, c.br, c.bvl, c.bvr, 2.0 * IG_U, c.bx0, out);
    for (int i = 0; i < c.nfb && c.cnt < n + 2; ++i) /* the undecided pieces' roots (sorted by the caller) */
        out[c.cnt++] = c.fb[i];
    return c.cnt;
}

int ig_bernstein_interval(const double *p, int n, double a, double b, int *fallbacks, double *out)
{
    return bernstein(p, n, a, b, 0, out, fallbacks);
}

int ig_bernstein_first(const double *p, int n, double a, double b, int *fallbacks, double *out)
{
    return bernstein(p, n, a, b, IG_FIRST_ROOT, out, fallbacks);
}

int ig_bernstein_any(const double *p, int n, double a, double b, int *fallbacks, double *out)
{
    return bernstein(p, n, a, b, IG_ANY_ROOT, out, fallbacks);
}
