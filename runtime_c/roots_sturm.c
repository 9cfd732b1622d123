/* Sturm-sequence isolation (after Hook & McAree, Graphics Gems I) with safeguarded refinement (ig_refine).
 *
 * The sequence p, p', -rem(p, p'), ... is built in floating point, each member scaled to a largest
 * coefficient of 1. A remainder whose coefficients are all within the rounding error of the division that
 * produced it ends the sequence: the last member is then (numerically) gcd(p, p'), and the variation count
 * still counts DISTINCT roots, so a tangent (double) root is counted once. [a, b] is bisected (in the
 * ordering of doubles) until each piece holds one root; a piece where p changes sign is refined by the same
 * ig_refine the bracketing method uses, so the two methods are compared at equal accuracy; a piece
 * without a sign change holds an even-multiplicity root and is narrowed by counting alone.
 */
#include "roots_impl.h"

#include <math.h>
#include <string.h>

typedef struct {
    int len;
    int deg[IG_MAX_DEGREE + 1];
    double c[IG_MAX_DEGREE + 1][IG_MAX_DEGREE + 1];
} sturm_seq;

static void normalise(double *c, int d)
{
    double m = 0.0;
    for (int i = 0; i <= d; ++i)
        if (fabs(c[i]) > m)
            m = fabs(c[i]);
    if (m > 0.0) {
        double s = ldexp(1.0, -ilogb(m)); /* a power of two: exact, so p(x) == 0 stays exactly zero */
        for (int i = 0; i <= d; ++i)
            c[i] *= s;
    }
}

static void build(const double *p, int n, sturm_seq *s)
{
    memcpy(s->c[0], p, (size_t)(n + 1) * sizeof(double));
    normalise(s->c[0], n);
    s->deg[0] = n;
    for (int k = 0; k < n; ++k)
        s->c[1][k] = (k + 1) * p[k + 1];
    normalise(s->c[1], n - 1);
    s->deg[1] = n - 1;
    s->len = 2;
    while (s->deg[s->len - 1] > 0) {
        const double *u = s->c[s->len - 2], *v = s->c[s->len - 1];
        int du = s->deg[s->len - 2], dv = s->deg[s->len - 1];
        double r[IG_MAX_DEGREE + 1];
        memcpy(r, u, (size_t)(du + 1) * sizeof(double));
        double big = 1.0; /* largest magnitude met in the division: sets the rounding scale */
        for (int i = du; i >= dv; --i) {
            double q = r[i] / v[dv];
            for (int j = 0; j <= dv; ++j) {
                double t = q * v[j];
                if (fabs(t) > big)
                    big = fabs(t);
                r[i - dv + j] -= t;
            }
        }
        double tol = 16.0 * (du + 1) * IG_U * big;
        int dr = dv - 1;
        while (dr >= 0 && fabs(r[dr]) <= tol)
            --dr;
        if (dr < 0)
            break; /* zero remainder: the last member is gcd(p, p') */
        double *w = s->c[s->len];
        for (int i = 0; i <= dr; ++i)
            w[i] = -r[i];
        normalise(w, dr);
        s->deg[s->len] = dr;
        s->len++;
    }
}

/* Sign variations at x; the sign of p itself is the certified one (zero within rounding counts as zero),
 * so a root at an end of the interval is counted consistently with the endpoint test. */
static int variations(const sturm_seq *s, double x)
{
    double v0;
    int prev = ig_sign_certified(s->c[0], s->deg[0], x, &v0);
    int count = 0;
    for (int k = 1; k < s->len; ++k) {
        double v = ig_horner(s->c[k], s->deg[k], x);
        int sg = (v > 0.0) - (v < 0.0);
        if (sg != 0) {
            if (prev != 0 && sg != prev)
                ++count;
            prev = sg;
        }
    }
    return count;
}

typedef struct {
    double l, r;
    int vl, vr;
} piece;

/* A root of even multiplicity alone in piece pc (one root by the count, no sign change): narrowed by
 * counting, then Newton on p', for which an even-multiplicity root of p is a root of odd multiplicity, kept
 * inside the piece. A floating-point Sturm count can be wrong: 1 with *x only when the zero is certified. */
static int even_root(const double *p, int n, const sturm_seq *s, piece pc, double *x)
{
    double l = pc.l, r = pc.r, d1[IG_MAX_DEGREE], vx;
    int vl = pc.vl;
    for (int it = 0; it < 80; ++it) {
        double m = ig_ordered_mid(l, r);
        if (!(m > l && m < r) || r - l <= 4.0 * IG_U * fabs(m))
            break;
        int vm = variations(s, m);
        if (vl - vm >= 1)
            r = m;
        else {
            l = m;
            vl = vm;
        }
    }
    /* the count is blind near a multiple root: finish with Newton on p' */
    *x = ig_ordered_mid(l, r);
    for (int j = 0; j < n; ++j)
        d1[j] = (j + 1) * p[j + 1];
    for (int it = 0; it < 8; ++it) {
        double v, dv;
        ig_horner2(d1, n - 1, *x, &v, &dv);
        double xn = *x - v / dv;
        if (v == 0.0 || !(xn >= pc.l && xn <= pc.r) || xn == *x)
            break;
        *x = xn;
    }
    return ig_sign_certified(p, n, *x, &vx) == 0;
}

/* The one root of piece pc: its right end when p vanishes there, the refined bracket when p changes sign, else a
 * root of even multiplicity. Returns 1 with *x, 0 when none is certified. */
static int single_root(const double *p, int n, const sturm_seq *s, piece pc, double *x)
{
    double fl, fr;
    int sl = ig_sign_certified(p, n, pc.l, &fl);
    int sr = ig_sign_certified(p, n, pc.r, &fr);
    if (sr == 0) {
        *x = pc.r;
        return 1;
    }
    if (sl * sr < 0) {
        *x = ig_refine(p, n, pc.l, pc.r, fl, fr, 2.0 * IG_U, NAN);
        return 1;
    }
    return even_root(p, n, s, pc, x);
}

int ig_sturm_interval(const double *p, int n, double a, double b, double *out)
{
    sturm_seq s;
    build(p, n, &s);
    int cnt = 0;
    double va;
    if (ig_sign_certified(p, n, a, &va) == 0)
        out[cnt++] = a;
    if (!(b > a))
        return cnt;
    piece st[4 * 64 + 2 * IG_MAX_DEGREE];
    int sp = 0;
    st[sp++] = (piece){a, b, variations(&s, a), variations(&s, b)};
    int budget = 64 * (n + 4); /* bound on variation counts: never loops without bound */
    while (sp > 0 && cnt <= n) {
        piece pc = st[--sp];
        int k = pc.vl - pc.vr;
        if (k <= 0)
            continue;
        if (k == 1) {
            double x;
            if (single_root(p, n, &s, pc, &x))
                out[cnt++] = x;
            continue;
        }
        double m = ig_ordered_mid(pc.l, pc.r);
        if (!(m > pc.l && m < pc.r) || --budget < 0 || sp + 2 > (int)(sizeof st / sizeof st[0])) {
            out[cnt++] = m; /* an unresolvable cluster: reported once */
            continue;
        }
        int vm = variations(&s, m);
        st[sp++] = (piece){m, pc.r, vm, pc.vr};
        st[sp++] = (piece){pc.l, m, pc.vl, vm};
    }
    return ig_sort_unique(out, cnt);
}
