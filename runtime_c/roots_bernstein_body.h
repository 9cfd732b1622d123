/* Body of the Bernstein-subdivision solver, included by roots_bernstein.c once per specialised degree.
 *
 * Before each inclusion define BZ_TAG (the suffix of the function names: a degree such as 4, or `any`) and,
 * for the any-degree version, BZ_ANY_DEGREE. With a fixed degree N is a constant and the O(n^2) loops are
 * unrolled completely (BZ_UNROLL), so the coefficients stay in registers; otherwise N is the run-time degree n. Every function takes n either way. Not a public
 * header: it has no include guard on purpose, and it undefines its macros at the end.
 */
#ifdef BZ_ANY_DEGREE
#define N n
#define BZ_FIXED_UNROLL
#else
#define N BZ_TAG
#define BZ_FIXED_UNROLL BZ_UNROLL
#endif
#define BZ_FN(name) BZ_CAT(name, BZ_TAG)

/* Bernstein coefficients of both halves of [m - rl, m + rr]: one Taylor shift to the midpoint m,
 * q(y) = p(m + y), then for each half the scaling y = +-r s and Pascal's triangle. L is written for [m - rl, m]
 * (left end first), R for [m, m + rr]. Shifting to the midpoint, not to an end, keeps the rounding at the scale
 * sum |p_k| max(|m - rl|, |m + rr|)^k (see bernstein()). */
static void BZ_FN(to_bernstein_mid)(const double *p, int n, double m, double rl, double rr, double *L, double *R)
{
    double t[IG_MAX_DEGREE + 1];
    (void)n;
    t[0] = p[0];
    for (int k = 1; k <= N; ++k)
        t[k] = p[k];
    BZ_FIXED_UNROLL
    for (int i = 0; i < N; ++i) { /* Taylor shift: t(y) = p(m + y), repeated synthetic division */
        BZ_FIXED_UNROLL
        for (int k = N - 1; k >= i; --k)
            t[k] += m * t[k + 1];
    }
    double fl = 1.0, fr = 1.0;   /* (-rl)^j / C(n, j), rr^j / C(n, j); C(n, j) = C(n, j - 1) (n - j + 1) / j */
    double W[IG_MAX_DEGREE + 1]; /* the left half in the reflected variable (0 at m, 1 at m - rl) */
    W[0] = t[0];
    R[0] = t[0];
    for (int j = 1; j <= N; ++j) {
        double f = j * bz_inv[N - j + 1];
        fl *= -rl * f;
        fr *= rr * f;
        W[j] = t[j] * fl;
        R[j] = t[j] * fr;
    }
    BZ_FIXED_UNROLL
    for (int k = 1; k <= N; ++k) { /* b_i = sum_j C(i, j) w_j: Pascal's triangle, additions only */
        BZ_FIXED_UNROLL
        for (int i = N; i >= k; --i) {
            W[i] += W[i - 1];
            R[i] += R[i - 1];
        }
    }
    for (int i = 0; i <= N; ++i)
        L[i] = W[N - i];
}

/* de Casteljau at s = 1/2: the halves' coefficients (weights 1/2: the only rounding is in the sums). */
static void BZ_FN(split_half)(const double *b, int n, double *L, double *R)
{
    double w[IG_MAX_DEGREE + 1];
    (void)n;
    w[0] = b[0];
    for (int i = 1; i <= N; ++i)
        w[i] = b[i];
    L[0] = w[0];
    R[N] = w[N];
    BZ_FIXED_UNROLL
    for (int k = 1; k <= N; ++k) {
        BZ_FIXED_UNROLL
        for (int i = 0; i <= N - k; ++i)
            w[i] = 0.5 * (w[i] + w[i + 1]);
        L[k] = w[0];
        R[N - k] = w[N - k];
    }
}

/* Sign changes of b[0..n] with end signs sl, sr (certain, nonzero), and in *unsure how many interior
 * coefficients are within tol of zero; -1 when uncertain interior coefficients
 * could hide changes: a run of them between two equal signs (+ ? + may be + - +), or a run of two or more
 * between opposite signs (+ ? ? - may be + - + -). A single one between opposite signs changes nothing. */
static int BZ_FN(variations)(const double *b, int n, double tol, int sl, int sr, int *unsure)
{
    int v = 0, last = sl, pending = 0;
    (void)n;
    /* the common case without branches on the data: every interior sign certain */
    int certain = 0, changes = 0, prev = sl > 0;
    for (int i = 1; i < N; ++i) {
        int pos = b[i] > 0.0;
        certain += fabs(b[i]) > tol;
        changes += pos != prev;
        prev = pos;
    }
    *unsure = N - 1 - certain;
    if (certain == N - 1)
        return changes + ((sr > 0) != prev);
    for (int i = 1; i < N; ++i) {
        if (!(fabs(b[i]) > tol)) {
            ++pending;
            continue;
        }
        int s = b[i] > 0.0 ? 1 : -1;
        if (pending > 1 || (pending == 1 && s == last))
            return -1;
        v += s != last;
        last = s;
        pending = 0;
    }
    if (pending > 1 || (pending == 1 && sr == last))
        return -1;
    return v + (sr != last);
}

/* Start guess for the one root of a piece: where the control polygon first crosses zero (the polygon lies
 * within O(h^2) of the curve, so this is close); NaN (false position) when no segment crosses. */
static double BZ_FN(polygon_crossing)(const double *b, int n, double tl, double tr)
{
    (void)n;
    /* one sign change (the caller's case): it follows the leading run of coefficients with b_0's sign */
    int i = 0, lead = b[0] > 0.0;
    for (int j = 1; j < N; ++j)
        i += (b[j] > 0.0) == lead;
    if ((b[i] > 0.0) != (b[i + 1] > 0.0) && b[i] != b[i + 1]) {
        double s = (i + b[i] / (b[i] - b[i + 1])) / N;
        return tl + s * (tr - tl);
    }
    return NAN;
}

/* Piece [tl, tr] with Bernstein coefficients b, each within tol of the exact ones, end signs sl, sr and values
 * vl, vr of p there. */
static void BZ_FN(piece)(bz_ctx *c, const double *b, double tl, double tr, int sl, int sr, double vl, double vr,
                         double tol, int depth)
{
    const int n = c->n;
    if (c->first && c->cnt + c->nfb > 0)
        return;
    if (c->first == IG_ANY_ROOT && sl != sr && any_inside(c, tl, tr)) /* certified signs that differ */
        return;
    int unsure;
    int v = BZ_FN(variations)(b, n, tol, sl, sr, &unsure);
    if (v == 0)
        return;
    if (v == 1) { /* one simple root: refined now in first-root mode, else with the others at the end */
        double x0 = BZ_FN(polygon_crossing)(b, n, tl, tr);
        if (c->first == IG_ANY_ROOT) { /* the root lies strictly inside (tl, tr): any point there says so */
            c->out[c->cnt++] = x0 > tl && x0 < tr ? x0 : 0.5 * tl + 0.5 * tr;
            return;
        }
        if (c->first) {
            c->out[c->cnt++] = ig_refine(c->p, n, tl, tr, vl, vr, 2.0 * IG_U, x0);
            return;
        }
        int k = c->cnt++;
        c->bl[k] = tl;
        c->br[k] = tr;
        c->bvl[k] = vl;
        c->bvr[k] = vr;
        c->bx0[k] = x0;
        return;
    }
    double tm = 0.5 * tl + 0.5 * tr;
    if (depth >= BZ_MAX_DEPTH || !(tm > tl && tm < tr)) {
        bz_fallback(c, tl, tr);
        return;
    }
    double L[IG_MAX_DEGREE + 1], R[IG_MAX_DEGREE + 1], vm;
    /* Coefficients of uncertain sign: converted afresh on this piece, the rounding is at the scale of p here,
     * sum |p_k| max(|tl|, |tr|)^k, which can be far below the inherited one (p small near the expansion point
     * of the ray polynomial, or a piece far from the larger end of the interval). */
    double tol_here = unsure > 0 ? 7.0 * N * IG_U * ig_horner_abs(c->p, n, ig_max(fabs(tl), fabs(tr))) : tol;
    if (tol_here < 0.25 * tol) {
        BZ_FN(to_bernstein_mid)(c->p, n, tm, tm - tl, tr - tm, L, R);
        tol = tol_here;
    } else {
        double big = 0.0;
        for (int i = 0; i <= N; ++i)
            big = ig_max(big, fabs(b[i]));
        BZ_FN(split_half)(b, n, L, R);
        /* the halving's own rounding: one per level of averages, each below u times the largest coefficient */
        tol += (N + 1) * IG_U * big;
    }
    int sm_sign = end_sign(c, L[N], tm, tol, &vm);
    if (sm_sign == 0) { /* p zero within rounding at the split point */
        bz_fallback(c, tl, tr);
        return;
    }
    BZ_FN(piece)(c, L, tl, tm, sl, sm_sign, vl, vm, tol, depth + 1);
    BZ_FN(piece)(c, R, tm, tr, sm_sign, sr, vm, vr, tol, depth + 1);
}

#undef BZ_FN
#undef BZ_FIXED_UNROLL
#undef N
#undef BZ_TAG
#ifdef BZ_ANY_DEGREE
#undef BZ_ANY_DEGREE
#endif
