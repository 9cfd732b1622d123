/* Test fixture shared by the C drivers of the root solvers: a polynomial from known roots. Header-only (static
 * functions); each driver is its own program. */
#ifndef IMPLGEN_TEST_POLY_FROM_ROOTS_H
#define IMPLGEN_TEST_POLY_FROM_ROOTS_H

/* c = prod (x - r_i) * prod (x^2 + b x + q) * scale, lowest power first; returns the degree */
static int from_roots(const double *r, int nr, double (*quad)[2], int nq, double scale, double *c)
{
    int n = 0;
    c[0] = scale;
    for (int i = 0; i < nr; ++i) {
        c[n + 1] = 0.0;
        for (int k = n + 1; k >= 1; --k)
            c[k] = c[k - 1] - r[i] * c[k];
        c[0] = -r[i] * c[0];
        ++n;
    }
    for (int i = 0; i < nq; ++i) {
        double b = quad[i][0], q = quad[i][1];
        c[n + 1] = c[n + 2] = 0.0;
        for (int k = n + 2; k >= 0; --k) {
            double v = q * c[k];
            if (k >= 1)
                v += b * c[k - 1];
            if (k >= 2)
                v += c[k - 2];
            c[k] = v;
        }
        n += 2;
    }
    return n;
}

#endif
