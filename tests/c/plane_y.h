/* Test fixture shared by the C drivers that need a ground: the plane f = y as a hand-written shape of degree 1
 * (its value, gradient and ray coefficients; each driver gives its own bounds). Header-only (static functions);
 * each driver is its own program. */
#ifndef IMPLGEN_TEST_PLANE_Y_H
#define IMPLGEN_TEST_PLANE_Y_H

/* f(o + t d) = o_y + t d_y, lowest power first */
static void plane_y_coeffs(const double o[3], const double d[3], const double *p, double *c)
{
    (void)p;
    c[0] = o[1];
    c[1] = d[1];
}

static double plane_y_value(const double q[3], const double *p)
{
    (void)p;
    return q[1];
}

static void plane_y_gradient(const double q[3], const double *p, double g[3])
{
    (void)q, (void)p;
    g[0] = g[2] = 0.0;
    g[1] = 1.0;
}

#endif
