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
 * Rounding: every b_i carries an error below tol = 24 n u M, M = sum |p_k| (|a| + |h|)^k (a priori bound of
 * the Taylor shift, the basis change and up to BZ_MAX_DEPTH halvings: about (6n + 3 + 12n) u M). A coefficient within tol of zero has no
 * certain sign. At the piece ends, where b_0 = p(t_l) and b_n = p(t_r), the compensated evaluation of
 * ig_sign_certified decides instead; inside, uncertain coefficients that might hide sign changes (see
 * variations()) force a split.
 *
 * Whenever this cannot conclude -- a piece still ambiguous after BZ_MAX_DEPTH halvings (a tangent or nearly
 * tangent ray, a cluster of roots), or p zero within rounding at a piece end -- the derivative-bracketing
 * solver (the one that reports tangent roots) takes over from the left end of that piece to b; the roots
 * already found left of it stand. Pieces are visited left to right in both modes, so the first root in
 * first-root mode is bitwise the first root of the full search.
 *
 * Speed: the body (roots_bernstein_body.h) is compiled once per degree 3 .. 12 with the degree a constant,
 * so the O(n^2) loops unroll into straight-line code, and once more for any degree.
 */
#include "roots_impl.h"

#include <math.h>
#include <string.h>

#define BZ_MAX_DEPTH 12

typedef struct {
    const double *p; /* power-form coefficients, exact degree n */
    int n;
    double a, h; /* the interval [a, a + h]; t = a + s h */
    double tol;  /* |b_i| <= tol: the sign of b_i is not certain */
    int first;   /* stop at the leftmost root */
    double *out;
    int cnt;
    double fallback_from; /* NaN, or the left end of the first piece that was not certain: bracketing decides
                           * from there on */
    /* all-roots mode: the isolating brackets (ends, values there, start guess), refined together at the end */
    double bl[IG_MAX_DEGREE], br[IG_MAX_DEGREE], bvl[IG_MAX_DEGREE], bvr[IG_MAX_DEGREE], bx0[IG_MAX_DEGREE];
} bz_ctx;

/* 1/k, k = 0 .. IG_MAX_DEGREE (entry 0 unused): turns the binomial scaling into products. */
static const double bz_inv[IG_MAX_DEGREE + 1] = {0.0,      1.0,      1.0 / 2,  1.0 / 3,  1.0 / 4,  1.0 / 5,  1.0 / 6,
                                                 1.0 / 7,  1.0 / 8,  1.0 / 9,  1.0 / 10, 1.0 / 11, 1.0 / 12, 1.0 / 13,
                                                 1.0 / 14, 1.0 / 15, 1.0 / 16, 1.0 / 17, 1.0 / 18, 1.0 / 19, 1.0 / 20,
                                                 1.0 / 21, 1.0 / 22, 1.0 / 23, 1.0 / 24};

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
#define BZ_TAG any
#define BZ_ANY_DEGREE
#include "roots_bernstein_body.h"

typedef void (*bz_piece_fn)(bz_ctx *c, const double *b, double s0, double s1, double tl, double tr, int sl, int sr,
                            double vl, double vr, int depth);
typedef void (*bz_basis_fn)(const double *p, int n, double a, double h, double *b);

/* The code specialised per degree (3 to 12); other degrees run the _any version. */
#define BZ_SPECIAL 13
#define BZ_ENTRY(d) [d] = {to_bernstein_##d, piece_##d}
static const struct {
    bz_basis_fn to_bernstein;
    bz_piece_fn piece;
} bz_special[BZ_SPECIAL] = {BZ_ENTRY(3), BZ_ENTRY(4), BZ_ENTRY(5),  BZ_ENTRY(6),  BZ_ENTRY(7),
                            BZ_ENTRY(8), BZ_ENTRY(9), BZ_ENTRY(10), BZ_ENTRY(11), BZ_ENTRY(12)};
#undef BZ_ENTRY

static int bernstein(const double *p, int n, double a, double b, int first, double *out)
{
    double h = b - a;
    if (!(h > 0.0) || !isfinite(h))
        return ig_bracket_interval(p, n, a, b, out);
    bz_ctx c;
    c.p = p;
    c.n = n;
    c.a = a;
    c.h = h;
    c.first = first;
    c.out = out;
    c.cnt = 0;
    c.fallback_from = NAN;
    double M = ig_horner_abs(p, n, fabs(a) + h);
    c.tol = 24.0 * n * IG_U * M;
    if (!isfinite(c.tol))
        return ig_bracket_interval(p, n, a, b, out);
    double bz[IG_MAX_DEGREE + 1], vl, vr;
    bz_basis_fn to_bernstein = to_bernstein_any;
    bz_piece_fn piece = piece_any;
    if (n < BZ_SPECIAL && bz_special[n].piece) {
        to_bernstein = bz_special[n].to_bernstein;
        piece = bz_special[n].piece;
    }
    to_bernstein(p, n, a, h, bz);
    int sl = end_sign(&c, bz[0], a, &vl), sr = end_sign(&c, bz[n], b, &vr);
    if (sl == 0 || sr == 0) /* a root at an end of the interval (within rounding) */
        return ig_bracket_interval(p, n, a, b, out);
    piece(&c, bz, 0.0, 1.0, a, b, sl, sr, vl, vr, 0);
    if (!first && c.cnt > 0) /* several roots in flight at once: about the time of one */
        ig_refine_many(p, n, c.cnt, c.bl, c.br, c.bvl, c.bvr, 2.0 * IG_U, c.bx0, out);
    if (!isnan(c.fallback_from)) /* the roots left of the unresolved piece stand; bracketing finds the rest */
        c.cnt += ig_bracket_interval(p, n, c.fallback_from, b, out + c.cnt);
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
