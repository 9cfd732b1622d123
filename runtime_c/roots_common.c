/* Pieces every root-finding method uses: Horner evaluation with the derivative, the certified sign of p(x)
 * (a compensated evaluation decides when plain Horner cannot), the quadratic without cancellation, and sorting
 * a root list.
 */
#include "roots_impl.h"

#include <float.h>
#include <math.h>

/* ---------------------------------------------------------------- evaluation */

void ig_horner2(const double *c, int n, double x, double *p, double *dp)
{
    if (n == 4) { /* the torus case, unrolled: same operations, no loop overhead */
        double v = c[4] * x + c[3], d = c[4];
        d = d * x + v;
        v = v * x + c[2];
        d = d * x + v;
        v = v * x + c[1];
        d = d * x + v;
        *p = v * x + c[0];
        *dp = d;
        return;
    }
    if (n == 3) {
        double v = c[3] * x + c[2], d = c[3];
        d = d * x + v;
        v = v * x + c[1];
        d = d * x + v;
        *p = v * x + c[0];
        *dp = d;
        return;
    }
    double v = c[n], d = 0.0;
    for (int k = n - 1; k >= 0; --k) {
        d = d * x + v;
        v = v * x + c[k];
    }
    *p = v;
    *dp = d;
}

int ig_sign_certified(const double *c, int n, double x, double *val)
{
    double v = c[n], s = fabs(c[n]), ax = fabs(x);
    for (int k = n - 1; k >= 0; --k) {
        v = v * x + c[k];
        s = s * ax + fabs(c[k]);
    }
    double g = 2.0 * n * IG_U;
    g = g / (1.0 - g); /* gamma_2n: a priori bound of Horner's relative error against sum |c_k||x|^k */
    double tiny = 2.0 * (n + 1) * DBL_MIN * IG_U; /* underflow allowance */
    *val = v;
    if (fabs(v) > g * s + tiny)
        return v > 0.0 ? 1 : -1;
    /* the compensated value: as accurate as Horner in twice the precision */
    double res = ig_horner_compensated(c, n, x);
    *val = res;
    if (fabs(res) > 2.0 * IG_U * fabs(res) + 2.0 * g * g * s + tiny)
        return res > 0.0 ? 1 : -1;
    return 0;
}

/* ---------------------------------------------------------------- quadratic, sorting */

int ig_quadratic(double c0, double c1, double c2, double *r)
{
    double b = -0.5 * c1; /* roots of c2 x^2 - 2 b x + c0 are (b +- sqrt(b^2 - c2 c0)) / c2 */
    double bb = b * b, ac = c2 * c0;
    double d = bb - ac;
    if (fabs(d) <= 4.0 * IG_U * (bb + fabs(ac))) {
        /* cancellation: redo the discriminant with exact products (Kahan), so its sign is right and a
         * double root of the given coefficients comes out as d == 0 */
        double pb, eb, pa, ea;
        ig_two_prod(b, b, &pb, &eb);
        ig_two_prod(c2, c0, &pa, &ea);
        d = (pb - pa) + (eb - ea);
    }
    if (!(d >= 0.0))
        return 0;
    int k;
    if (d == 0.0) {
        r[0] = b / c2;
        k = 1;
    } else {
        double q = b + copysign(sqrt(d), b); /* no cancellation; q != 0 because d > 0 */
        double x1 = q / c2, x2 = c0 / q;
        if (x1 > x2) {
            double t = x1;
            x1 = x2;
            x2 = t;
        }
        r[0] = x1;
        r[1] = x2;
        k = (x1 == x2) ? 1 : 2;
    }
    int m = 0; /* a root beyond DBL_MAX is not representable: drop it */
    for (int i = 0; i < k; ++i)
        if (isfinite(r[i]))
            r[m++] = r[i];
    return m;
}

void ig_sort(double *r, int k)
{
    for (int i = 1; i < k; ++i) {
        double x = r[i];
        int j = i - 1;
        while (j >= 0 && r[j] > x) {
            r[j + 1] = r[j];
            --j;
        }
        r[j + 1] = x;
    }
}

int ig_sort_unique(double *r, int k)
{
    ig_sort(r, k);
    int m = 0;
    for (int i = 0; i < k; ++i)
        if (m == 0 || r[i] != r[m - 1])
            r[m++] = r[i];
    return m;
}
