/* The polynomial certificate (certify.h, docs/certify.md): a polynomial known as coefficient balls -- each true
 * coefficient within e[k] of c[k] -- is written in the Bernstein basis of [a, b] in ball arithmetic, then cut in
 * halves by de Casteljau's rule, left half first. A piece whose Bernstein balls all lie on one side of zero
 * holds no root (the polynomial is a convex combination of them); a piece whose first and last balls have
 * opposite signs and whose balls can show only one sign change, whatever the true values inside them, holds
 * exactly one root, a simple one (Descartes' rule in the Bernstein basis). Every operation's rounding is added
 * to the radius (errarith.h's constants), so what is proved holds for every polynomial inside the balls.
 */
#include "certify.h"
#include "errarith.h"
#include "numerics.h"
#include "roots.h"

#include <math.h>

#define CERT_MAX_DEPTH 48 /* pieces down to 2^-48 of [a, b] */
#define CERT_BUDGET 800   /* pieces looked at per call */

typedef struct {
    double m, r;
} ball;

static inline ball b_add(ball x, ball y)
{
    ball z;
    z.m = x.m + y.m;
    z.r = (x.r + y.r + IG_ERR_U * fabs(z.m)) * IG_ERR_G;
    return z;
}

static inline ball b_mul(ball x, ball y)
{
    ball z;
    z.m = x.m * y.m;
    z.r = (fabs(x.m) * y.r + fabs(y.m) * x.r + x.r * y.r + IG_ERR_U * fabs(z.m) + IG_ERR_ETA) * IG_ERR_G;
    return z;
}

static inline ball b_half_sum(ball x, ball y)
{
    ball z;
    z.m = 0.5 * (x.m + y.m);
    z.r = (0.5 * (x.r + y.r) + IG_ERR_U * fabs(z.m) + IG_ERR_ETA) * IG_ERR_G;
    return z;
}

/* -1, +1: the ball lies below or above zero; 0: it holds zero (or is not finite). */
static inline int b_sign(ball x) { return x.m > x.r ? 1 : (x.m < -x.r ? -1 : 0); }

/* q(x) = p(a + x) in ball arithmetic: q's balls in q. */
static void taylor_plain(const double *c, const double *e, int n, double a, ball *q)
{
    ball A = {a, 0.0};
    int i, k;
    for (k = 0; k <= n; ++k) {
        q[k].m = c[k];
        q[k].r = e[k];
    }
    for (i = 0; i < n; ++i)
        for (k = n - 1; k >= i; --k)
            q[k] = b_add(q[k], b_mul(A, q[k + 1]));
}

/* The same compensated (the sign the plain shift cannot decide, where |a|^k |c_k| dwarfs the values: a ray
 * polynomial written far from the object): every coefficient is carried as an unevaluated sum h + l of two
 * doubles (error-free sums and products of numerics.h), so each step loses about u^2 of its terms' size instead
 * of u. The step q[k] += a q[k+1]: h0 + a h1 = s + e1 + e2 exactly (TwoProd, TwoSum); the low parts
 * l0 + a l1 + e1 + e2 are summed in double, at most four roundings of at most u times their absolute sum
 * each. */
static void taylor_compensated(const double *c, const double *e, int n, double a, ball *q)
{
    double h[IG_MAX_DEGREE + 1], l[IG_MAX_DEGREE + 1], r[IG_MAX_DEGREE + 1];
    int i, k;
    for (k = 0; k <= n; ++k) {
        h[k] = c[k];
        l[k] = 0.0;
        /* TwoProd splits its factors: exact only below 2^996 */
        r[k] = fabs(c[k]) < 1e250 && fabs(a) < 1e250 ? e[k] : INFINITY;
    }
    for (i = 0; i < n; ++i)
        for (k = n - 1; k >= i; --k) {
            double p, pe, s, se, al = a * l[k + 1], lo, mag;
            ig_two_prod(a, h[k + 1], &p, &pe);
            ig_two_sum(h[k], p, &s, &se);
            lo = ((l[k] + al) + se) + pe;
            mag = fabs(l[k]) + fabs(al) + fabs(se) + fabs(pe);
            r[k] = (r[k] + fabs(a) * r[k + 1] + 5.0 * IG_ERR_U * mag + 4.0 * IG_ERR_ETA) * IG_ERR_G;
            ig_two_sum(s, lo, &h[k], &l[k]); /* renormalised: exact */
        }
    for (k = 0; k <= n; ++k) {
        q[k].m = h[k] + l[k];
        q[k].r = (r[k] + fabs(q[k].m - h[k] - l[k]) + IG_ERR_U * fabs(q[k].m)) * IG_ERR_G;
    }
}

/* The Bernstein balls of p on [a, b]: p(a + h y) = sum_i B[i] C(n, i) y^i (1 - y)^(n - i), h = b - a. The Taylor
 * shift plain, or compensated; worked in place in B. */
static void to_bernstein(const double *c, const double *e, int n, double a, double b, int compensated, ball *B)
{
    ball h, hp = {1.0, 0.0};
    double cnk = 1.0;
    int i, k;
    if (compensated)
        taylor_compensated(c, e, n, a, B);
    else
        taylor_plain(c, e, n, a, B);
    h.m = b - a;
    h.r = IG_ERR_U * fabs(h.m);
    /* x = h y, then B[i] = sum_k C(i, k) q[k] / C(n, k): q[k] divided by C(n, k) (an exact integer below 2^53),
     * and the sums with C(i, k) as Pascal's triangle builds them, by additions only */
    for (k = 1; k <= n; ++k) {
        ball q;
        hp = b_mul(hp, h);
        q = b_mul(B[k], hp);
        cnk = cnk * (double)(n - k + 1) / (double)k; /* C(n, k) from C(n, k - 1): exact */
        B[k].m = q.m / cnk;
        B[k].r = (q.r / cnk + IG_ERR_U * fabs(B[k].m) + IG_ERR_ETA) * IG_ERR_G;
    }
    for (i = 1; i <= n; ++i)
        for (k = n; k >= i; --k)
            B[k] = b_add(B[k], B[k - 1]);
}

/* de Casteljau at y = 1/2: B's left half into L, right half into R. */
static void split(const ball *B, int n, ball *L, ball *R)
{
    ball t[IG_MAX_DEGREE + 1];
    int i, k;
    if (n < 0 || n > IG_MAX_DEGREE)
        return;
    for (i = 0; i <= n; ++i)
        t[i] = B[i];
    L[0] = B[0];
    R[n] = B[n];
    for (k = 1; k <= n; ++k) {
        for (i = 0; i + k <= n; ++i)
            t[i] = b_half_sum(t[i], t[i + 1]);
        L[k] = t[0];
        R[n - k] = t[n - k];
    }
}

enum { PIECE_EMPTY = 0, PIECE_ONE = 1, PIECE_OPEN = 2, PIECE_BAD = 3 };

/* What a piece's balls prove: no root, exactly one simple root, nothing yet, or a ball not finite. */
static int classify(const ball *B, int n)
{
    int i, s0 = b_sign(B[0]), sn = b_sign(B[n]), last = 0, changes = 0, wild = 0, any = 0;
    for (i = 0; i <= n; ++i)
        if (!(fabs(B[i].m) <= 1e300) || !(B[i].r <= 1e300))
            return PIECE_BAD;
    for (i = 0; i <= n; ++i) {
        int sg = b_sign(B[i]);
        if (sg == 0) {
            any = 1;
            wild = 1;
            continue;
        }
        if (last != 0 && sg != last)
            ++changes;
        else if (last != 0 && wild)
            changes += 2; /* a zero-holding run between equal signs could hide two changes */
        last = sg;
        wild = 0;
    }
    if (!any && changes == 0)
        return PIECE_EMPTY;
    if (s0 != 0 && sn != 0 && s0 != sn && changes == 1)
        return PIECE_ONE;
    return PIECE_OPEN;
}

/* The polynomial a walk works on: its coefficient balls, and whether its Taylor shifts are compensated. */
typedef struct {
    const double *c, *e;
    int n, compensated;
} poly;

/* A piece: the Bernstein balls of exactly [lo, hi] (both doubles); fresh: computed from the coefficients, not
 * by de Casteljau (whose radii only grow as pieces shrink). */
typedef struct {
    ball B[IG_MAX_DEGREE + 1];
    double lo, hi;
    int depth, fresh;
} piece;

static void form(const poly *P, piece *p)
{
    to_bernstein(P->c, P->e, P->n, p->lo, p->hi, P->compensated, p->B);
    p->fresh = 1;
}

/* p cut in two: its left half stays in p, its right half goes to R. At the exact midpoint when that is a double
 * (de Casteljau at y = 1/2), else at the double nearest it (both halves' forms from the coefficients). 0, with
 * p unchanged, when no double lies strictly between the ends. */
static int halve(const poly *P, piece *p, piece *R)
{
    double s, e, m;
    ig_two_sum(p->lo, p->hi, &s, &e);
    m = 0.5 * s;
    if (e == 0.0 && 2.0 * m == s && m > p->lo && m < p->hi) {
        split(p->B, P->n, p->B, R->B);
        R->lo = m;
        R->hi = p->hi;
        p->hi = m;
        R->depth = ++p->depth;
        p->fresh = R->fresh = 0;
        return 1;
    }
    m = 0.5 * p->lo + 0.5 * p->hi;
    if (!(m > p->lo && m < p->hi))
        return 0;
    R->lo = m;
    R->hi = p->hi;
    p->hi = m;
    R->depth = ++p->depth;
    form(P, p);
    form(P, R);
    return 1;
}

/* Why a piece could not be decided: its end at a or b undecided (a root within the noise of the range's end),
 * or a root there that is not simple, or a cluster the depth cannot part. */
static int open_reason(const piece *p, int n, int first_piece, int last_piece)
{
    if ((first_piece && b_sign(p->B[0]) == 0) || (last_piece && b_sign(p->B[n]) == 0))
        return RT_CERT_NOISE;
    return RT_CERT_TANGENT;
}

/* A piece holding one simple root cut down, half by half, to the half that holds it, until it is at most rel x
 * |origin + its start| wide (the caller's parameter is origin + s) or its halves no longer tell. */
static void narrow(const poly *P, piece *p, double origin, double rel)
{
    while (p->depth < CERT_MAX_DEPTH && p->hi - p->lo > rel * fabs(origin + p->lo)) {
        piece L = *p, R;
        int kl, kr;
        if (!halve(P, &L, &R))
            return;
        kl = classify(L.B, P->n);
        kr = classify(R.B, P->n);
        if (kl == PIECE_ONE && kr == PIECE_EMPTY)
            *p = L;
        else if (kl == PIECE_EMPTY && kr == PIECE_ONE)
            *p = R;
        else
            return;
    }
}

/* Do the balls' radii matter: some radius above 1e-3 of the largest centre? */
static int noisy(const ball *B, int n)
{
    double m = 0.0, r = 0.0;
    int i;
    for (i = 0; i <= n; ++i) {
        m = ig_max(m, fabs(B[i].m));
        r = ig_max(r, B[i].r);
    }
    return r > 1e-3 * m;
}

/* What a piece proves; an open piece deep enough whose form came by de Casteljau, with radii that matter, is
 * formed afresh first. */
static int piece_kind(const poly *P, piece *p)
{
    int kind = classify(p->B, P->n);
    if (kind == PIECE_OPEN && !p->fresh && p->depth % 4 == 0 && noisy(p->B, P->n)) {
        form(P, p);
        kind = classify(p->B, P->n);
    }
    return kind;
}

/* Left-first walk over the pieces of [a, b]. max_roots: stop after that many root pieces. Writes the root
 * intervals (each exactly a piece: no rounding); returns their count, or -code with lo[count] .. hi[count] the
 * undecided piece. */
static int walk(const poly *P, double a, double b, int max_roots, double origin, double rel, double *lo, double *hi)
{
    piece stack[CERT_MAX_DEPTH + 2], cur;
    int sp = 0, found = 0, budget = CERT_BUDGET;
    if (!(a <= b) || P->n < 0 || P->n > IG_MAX_DEGREE)
        return -RT_CERT_OVERFLOW;
    cur.lo = a;
    cur.hi = b;
    cur.depth = 0;
    form(P, &cur);
    for (;;) {
        int kind = piece_kind(P, &cur);
        if (kind == PIECE_BAD || kind == PIECE_OPEN) {
            int code = kind == PIECE_BAD ? RT_CERT_OVERFLOW : 0;
            if (!code && (cur.depth >= CERT_MAX_DEPTH || --budget <= 0 || !halve(P, &cur, &stack[sp])))
                code = budget <= 0 ? RT_CERT_BUDGET : open_reason(&cur, P->n, cur.lo == a, cur.hi == b);
            if (code) {
                lo[found] = cur.lo;
                hi[found] = cur.hi;
                return -code;
            }
            ++sp;
            continue;
        }
        if (kind == PIECE_ONE) {
            narrow(P, &cur, origin, rel);
            lo[found] = cur.lo;
            hi[found] = cur.hi;
            if (++found >= max_roots)
                return found;
        }
        if (sp == 0)
            return found;
        cur = stack[--sp];
    }
}

/* A line c0 + c1 s with |C1| > e1: its one root -C0 / C1 lies between the quotients of the balls' corners (each
 * rounded outward). 1 and the interval when that lies inside (a, b), 0 when it misses [a, b], -1: undecided. */
static int line_root(const double *c, const double *e, double a, double b, double *lo, double *hi)
{
    double q[4], l = INFINITY, h = -INFINITY;
    int i;
    if (!(fabs(c[1]) > e[1]) || !(fabs(c[0]) + e[0] <= 1e300) || !(fabs(c[1]) <= 1e300))
        return -1;
    q[0] = -(c[0] - e[0]) / (c[1] - e[1]);
    q[1] = -(c[0] - e[0]) / (c[1] + e[1]);
    q[2] = -(c[0] + e[0]) / (c[1] - e[1]);
    q[3] = -(c[0] + e[0]) / (c[1] + e[1]);
    for (i = 0; i < 4; ++i) {
        l = q[i] < l ? q[i] : l;
        h = q[i] > h ? q[i] : h;
    }
    l -= 4.0 * IG_ERR_U * fabs(l) + IG_ERR_ETA;
    h += 4.0 * IG_ERR_U * fabs(h) + IG_ERR_ETA;
    if (l > a && h < b) {
        *lo = l;
        *hi = h;
        return 1;
    }
    return (h < a || l > b) ? 0 : -1;
}

int rt_certify_first_root(const double *c, const double *e, int n, double a, double b, double origin, double rel,
                          double *lo, double *hi)
{
    double l[2] = {a, a}, h[2] = {b, b};
    poly P = {c, e, n, 0};
    int k = n == 1 ? line_root(c, e, a, b, lo, hi) : -1;
    if (k >= 0)
        return k;
    k = walk(&P, a, b, 1, origin, rel, l, h);
    if (k < 0 && k != -RT_CERT_OVERFLOW) { /* the plain shift could not decide: again, compensated */
        P.compensated = 1;
        k = walk(&P, a, b, 1, origin, rel, l, h);
    }
    *lo = l[0];
    *hi = k < 0 ? l[0] : h[0];
    return k;
}

int rt_certify_roots(const double *c, const double *e, int n, double a, double b, double origin, double rel, double *lo,
                     double *hi, int *sign_a)
{
    ball B[IG_MAX_DEGREE + 1];
    poly P = {c, e, n, 0};
    int k;
    if (!(a <= b) || n < 0 || n > IG_MAX_DEGREE)
        return -RT_CERT_OVERFLOW;
    to_bernstein(c, e, n, a, b, 1, B);
    *sign_a = b_sign(B[0]);
    k = walk(&P, a, b, n + 1, origin, rel, lo, hi);
    if (k < 0 && k != -RT_CERT_OVERFLOW) {
        P.compensated = 1;
        k = walk(&P, a, b, n + 1, origin, rel, lo, hi);
    }
    if (k >= 0 && *sign_a == 0)
        return -RT_CERT_NOISE;
    return k;
}
