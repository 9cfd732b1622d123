/* Closed forms for cubics and quartics.
 *
 * Polished (IG_ROOTS_CLOSED):
 *   - the polynomial is made monic in a scaled variable x = 2^e y chosen from the binary exponents so every
 *     monic coefficient is below 2 in magnitude: no overflow, and the roots are O(1);
 *   - cubic: one real root from Cardano or the trigonometric form, Newton-polished, then deflated with the
 *     relatively accurate product c1 = -a0 / x1 (Kahan's advice), the quadratic solved without cancellation;
 *   - quartic: Ferrari's factorisation into two quadratics from the largest root of the resolvent cubic, then
 *     the factorisation itself refined by Newton's method on the four equations
 *       a1 + a2 = A, b1 + b2 + a1 a2 = B, a1 b2 + a2 b1 = C, b1 b2 = D
 *     (the idea of Orellana & De Michele, Algorithm 1010), which repairs the accuracy Ferrari loses;
 *   - a quadratic factor whose discriminant is zero within rounding is a tangent candidate, accepted only when
 *     the polynomial is zero there within the compensated-evaluation bound;
 *   - every real root gets up to two Newton steps on the original (scaled) polynomial, kept only when they
 *     lower |p|.
 * Plain (bench-only IG_ROOTS_CLOSED_PLAIN): the classic textbook forms as in Schwarze's Graphics Gems code --
 * divide by the leading coefficient, depress, Cardano / trigonometric cubic, Ferrari quartic, absolute 1e-9
 * "is zero" tests, no polishing. It is the speed baseline of the solver report.
 */
#include "roots_impl.h"

#include <limits.h>
#include <math.h>

static const double IG_PI = 3.14159265358979323846;

/* Real roots of the monic cubic y^3 + a2 y^2 + a1 y + a0, unpolished, in no particular order. Returns the
 * count (1 or 3). *re_pair, when the count is 1, gets the real part of the complex pair. */
static int cubic_monic_raw(double a2, double a1, double a0, double *y, double *re_pair)
{
    double s = a2 / 3.0;
    double Q = (a2 * a2 - 3.0 * a1) / 9.0;
    double R = (a2 * (2.0 * a2 * a2 - 9.0 * a1) + 27.0 * a0) / 54.0;
    double Q3 = Q * Q * Q, R2 = R * R;
    if (R2 < Q3) {
        double t = R / sqrt(Q3);
        if (t > 1.0)
            t = 1.0;
        if (t < -1.0)
            t = -1.0;
        double th = acos(t) / 3.0, m = -2.0 * sqrt(Q);
        y[0] = m * cos(th) - s;
        y[1] = m * cos(th + 2.0 * IG_PI / 3.0) - s;
        y[2] = m * cos(th - 2.0 * IG_PI / 3.0) - s;
        return 3;
    }
    double A = -copysign(cbrt(fabs(R) + sqrt(R2 - Q3)), R);
    double B = A != 0.0 ? Q / A : 0.0;
    y[0] = (A + B) - s;
    *re_pair = -0.5 * (A + B) - s;
    return 1;
}

/* x = 2^e y with a[0..n-1] the monic coefficients in y, each below 2 in magnitude; a[n] = 1. Returns e. */
static int monic_scaled(const double *c, int n, double *a)
{
    int en, ek, e = INT_MIN;
    double mn = frexp(c[n], &en);
    for (int k = 0; k < n; ++k) {
        if (c[k] == 0.0)
            continue;
        frexp(c[k], &ek);
        int num = ek - en, den = n - k;
        int q = num >= 0 ? (num + den - 1) / den : -((-num) / den); /* ceil(num / den) */
        if (q > e)
            e = q;
    }
    if (e == INT_MIN)
        e = 0;
    for (int k = 0; k < n; ++k) {
        if (c[k] == 0.0) {
            a[k] = 0.0;
            continue;
        }
        double mk = frexp(c[k], &ek);
        a[k] = ldexp(mk / mn, ek - en - e * (n - k));
    }
    a[n] = 1.0;
    return e;
}

/* Newton steps on a (degree n), each kept only when it lowers |p|. */
static double polish(const double *a, int n, double x, int steps)
{
    double v, dv;
    ig_horner2(a, n, x, &v, &dv);
    for (int s = 0; s < steps && v != 0.0 && dv != 0.0; ++s) {
        double xn = x - v / dv, vn, dvn;
        ig_horner2(a, n, xn, &vn, &dvn);
        if (!(fabs(vn) < fabs(v)))
            break;
        x = xn;
        v = vn;
        dv = dvn;
    }
    return x;
}

/* Roots of the factor y^2 + al y + be of poly (degree n); a discriminant that is zero within rounding is a
 * tangent only when poly is certified zero at -al/2. Appends to r, returns the count. */
static int factor_roots(double al, double be, const double *poly, int n, double *r)
{
    double h = -0.5 * al;
    double d = h * h - be;
    if (fabs(d) <= 32.0 * IG_U * (h * h + fabs(be))) {
        double v;
        if (ig_sign_certified(poly, n, h, &v) == 0) {
            r[0] = h;
            return 1;
        }
        if (d < 0.0)
            return 0;
    } else if (d < 0.0) {
        return 0;
    }
    return ig_quadratic(be, al, 1.0, r);
}

static int finish(double *y, int k, int e, double lo, double hi, double *r)
{
    int m = 0;
    for (int i = 0; i < k; ++i) {
        double x = ldexp(y[i], e);
        if (x >= lo && x <= hi && isfinite(x))
            r[m++] = x;
    }
    return ig_sort_unique(r, m);
}

/* ------------------------------------------------------------------------------------------- plain */

static int is_zero_classic(double x) { return x > -1e-9 && x < 1e-9; }

/* *r = sqrt(x), with x within 1e-9 of zero taken as zero; 0 when x is negative (no real square root). */
static int sqrt_classic(double x, double *r)
{
    if (is_zero_classic(x))
        *r = 0.0;
    else if (x > 0.0)
        *r = sqrt(x);
    else
        return 0;
    return 1;
}

/* Classic cubic on the monic x^3 + A x^2 + B x + C (Cardano, trigonometric for three real roots). */
static int cubic_classic(double A, double B, double C, double *x)
{
    double sub = A / 3.0;
    double p = (B - A * sub) / 3.0; /* depressed y^3 + 3p y + 2q */
    double q = 0.5 * (2.0 / 27.0 * A * A * A - A * B / 3.0 + C);
    double D = q * q + p * p * p;
    int k;
    if (is_zero_classic(D)) {
        if (is_zero_classic(q)) {
            x[0] = 0.0;
            k = 1;
        } else {
            double u = cbrt(-q);
            x[0] = 2.0 * u;
            x[1] = -u;
            k = 2;
        }
    } else if (D < 0.0) {
        double phi = acos(-q / sqrt(-p * p * p)) / 3.0, t = 2.0 * sqrt(-p);
        x[0] = t * cos(phi);
        x[1] = -t * cos(phi + IG_PI / 3.0);
        x[2] = -t * cos(phi - IG_PI / 3.0);
        k = 3;
    } else {
        double sd = sqrt(D);
        x[0] = cbrt(sd - q) - cbrt(sd + q);
        k = 1;
    }
    for (int i = 0; i < k; ++i)
        x[i] -= sub;
    return k;
}

static int quartic_classic(const double *c, double *x)
{
    double A = c[3] / c[4], B = c[2] / c[4], C = c[1] / c[4], D = c[0] / c[4];
    double sA = A * A;
    double p = -3.0 / 8.0 * sA + B;
    double q = 1.0 / 8.0 * sA * A - 0.5 * A * B + C;
    double r = -3.0 / 256.0 * sA * sA + 1.0 / 16.0 * sA * B - 0.25 * A * C + D;
    int k = 0;
    if (is_zero_classic(r)) {
        k = cubic_classic(0.0, p, q, x); /* z (z^3 + p z + q) */
        x[k++] = 0.0;
    } else {
        /* resolvent z^3 - p/2 z^2 - r z + (r p / 2 - q^2 / 8) */
        double zs[3];
        cubic_classic(-0.5 * p, -r, 0.5 * r * p - 0.125 * q * q, zs);
        double z = zs[0];
        double u = z * z - r, v = 2.0 * z - p;
        if (!sqrt_classic(u, &u) || !sqrt_classic(v, &v))
            return 0;
        double w = q < 0.0 ? -u : u; /* (x^2 + z)^2 - (v x - w)^2 with 2 v w = q */
        double qa[2][2] = {{z + w, -v}, {z - w, v}};
        for (int f = 0; f < 2; ++f) {
            double c0 = qa[f][0], c1 = qa[f][1];
            double disc = 0.25 * c1 * c1 - c0;
            if (is_zero_classic(disc)) {
                x[k++] = -0.5 * c1;
            } else if (disc > 0.0) {
                double sd = sqrt(disc);
                x[k++] = sd - 0.5 * c1;
                x[k++] = -sd - 0.5 * c1;
            }
        }
    }
    for (int i = 0; i < k; ++i)
        x[i] -= 0.25 * A;
    return k;
}

/* ------------------------------------------------------------------------------------------- public */

int ig_closed_cubic(const double *c, double lo, double hi, int polish_on, double *r)
{
    double y[4] = {0.0, 0.0, 0.0, 0.0};
    if (!polish_on) {
        int k = cubic_classic(c[2] / c[3], c[1] / c[3], c[0] / c[3], y);
        return finish(y, k, 0, lo, hi, r);
    }
    double a[4], re = 0.0;
    int e = monic_scaled(c, 3, a);
    int k = cubic_monic_raw(a[2], a[1], a[0], y, &re);
    /* deflate by the real root of largest magnitude */
    int big = 0;
    for (int i = 1; i < k; ++i)
        if (fabs(y[i]) > fabs(y[big]))
            big = i;
    double x1 = polish(a, 3, y[big], 3);
    double out[4];
    int m = 0;
    out[m++] = x1;
    if (x1 != 0.0) {
        double b1 = a[2] + x1, c1 = -a[0] / x1; /* y^2 + b1 y + c1 holds the other two roots */
        double q[2];
        int kq = factor_roots(b1, c1, a, 3, q);
        for (int i = 0; i < kq; ++i)
            out[m++] = polish(a, 3, q[i], 2);
    }
    return finish(out, m, e, lo, hi, r);
}

/* One Newton step on the factorisation (y^2 + f[0] y + f[1]) (y^2 + f[2] y + f[3]) = monic quartic. */
static double factor_residual(const double *f, const double *a, double *F)
{
    F[0] = f[0] + f[2] - a[3];
    F[1] = f[1] + f[3] + f[0] * f[2] - a[2];
    F[2] = f[0] * f[3] + f[2] * f[1] - a[1];
    F[3] = f[1] * f[3] - a[0];
    return fabs(F[0]) + fabs(F[1]) + fabs(F[2]) + fabs(F[3]);
}

static void refine_factors(const double *a, double *f)
{
    double F[4];
    double res = factor_residual(f, a, F);
    for (int it = 0; it < 4 && res > 0.0; ++it) {
        /* Jacobian in the unknowns (al1, be1, al2, be2) */
        double J[4][5] = {{1.0, 0.0, 1.0, 0.0, F[0]},
                          {f[2], 1.0, f[0], 1.0, F[1]},
                          {f[3], f[2], f[1], f[0], F[2]},
                          {0.0, f[3], 0.0, f[1], F[3]}};
        int ok = 1;
        for (int col = 0; col < 4 && ok; ++col) {
            int piv = col;
            for (int row = col + 1; row < 4; ++row)
                if (fabs(J[row][col]) > fabs(J[piv][col]))
                    piv = row;
            if (J[piv][col] == 0.0) {
                ok = 0;
                break;
            }
            if (piv != col)
                for (int j = 0; j < 5; ++j) {
                    double t = J[col][j];
                    J[col][j] = J[piv][j];
                    J[piv][j] = t;
                }
            for (int row = col + 1; row < 4; ++row) {
                double m = J[row][col] / J[col][col];
                for (int j = col; j < 5; ++j)
                    J[row][j] -= m * J[col][j];
            }
        }
        if (!ok)
            return;
        double dlt[4];
        for (int row = 3; row >= 0; --row) {
            double s = J[row][4];
            for (int j = row + 1; j < 4; ++j)
                s -= J[row][j] * dlt[j];
            dlt[row] = s / J[row][row];
        }
        double g[4], G[4];
        for (int i = 0; i < 4; ++i)
            g[i] = f[i] - dlt[i];
        double rn = factor_residual(g, a, G);
        if (!(rn < res))
            return;
        for (int i = 0; i < 4; ++i) {
            f[i] = g[i];
            F[i] = G[i];
        }
        res = rn;
    }
}

int ig_closed_quartic(const double *c, double lo, double hi, int polish_on, double *r)
{
    if (!polish_on) {
        double y[4];
        int k = quartic_classic(c, y);
        return finish(y, k, 0, lo, hi, r);
    }
    double a[5];
    int e = monic_scaled(c, 4, a);
    double A = a[3], B = a[2], C = a[1], D = a[0];
    double A2 = A * A;
    /* depressed z^4 + p z^2 + q z + s with y = z - A/4 */
    double p = B - 0.375 * A2;
    double q = C - 0.5 * A * B + 0.125 * A2 * A;
    double s = D - 0.25 * A * C + 0.0625 * A2 * B - 3.0 / 256.0 * A2 * A2;
    double f[4]; /* al1, be1, al2, be2 */
    /* resolvent m^3 + p m^2 + (p^2/4 - s) m - q^2/8: the largest root m >= 0 makes the split exact */
    double rc[4] = {-0.125 * q * q, 0.25 * p * p - s, p, 1.0};
    double ms[3], re = 0.0;
    int km = cubic_monic_raw(rc[2], rc[1], rc[0], ms, &re);
    double m = ms[0];
    for (int i = 1; i < km; ++i)
        if (ms[i] > m)
            m = ms[i];
    m = polish(rc, 3, m, 2);
    if (m > 0.0 && q != 0.0) {
        double w = sqrt(2.0 * m), t = q / (2.0 * w);
        double t1 = 0.5 * p + m - t, t2 = 0.5 * p + m + t; /* z^2 + w z + t1, z^2 - w z + t2 */
        f[0] = 0.5 * A + w;
        f[1] = 0.0625 * A2 + 0.25 * w * A + t1;
        f[2] = 0.5 * A - w;
        f[3] = 0.0625 * A2 - 0.25 * w * A + t2;
    } else {
        /* biquadratic z^4 + p z^2 + s */
        double disc = p * p - 4.0 * s;
        if (disc >= 0.0) {
            double qq = -0.5 * (p + copysign(sqrt(disc), p));
            double w1 = qq, w2 = qq != 0.0 ? s / qq : 0.0; /* z^2 = w */
            f[0] = f[2] = 0.5 * A;
            f[1] = 0.0625 * A2 - w1;
            f[3] = 0.0625 * A2 - w2;
        } else {
            double sr = sqrt(s), g = sqrt(fmax(2.0 * sr - p, 0.0)); /* (z^2 + sr)^2 - g^2 z^2 */
            f[0] = 0.5 * A + g;
            f[1] = 0.0625 * A2 + 0.25 * g * A + sr;
            f[2] = 0.5 * A - g;
            f[3] = 0.0625 * A2 - 0.25 * g * A + sr;
        }
    }
    refine_factors(a, f);
    double y[4];
    int k = factor_roots(f[0], f[1], a, 4, y);
    k += factor_roots(f[2], f[3], a, 4, y + k);
    for (int i = 0; i < k; ++i)
        y[i] = polish(a, 4, y[i], 2);
    return finish(y, k, e, lo, hi, r);
}
