/* A hand-made torus ig_shape (Suffern, "Ray Tracing from the Ground Up", eq. 19.20-19.22: axis y, swept
 * radius a, tube radius b; params = {a, b}). Stands in for the generated torus until generated/torus_y.c
 * exists; the test can then link the generated one instead. */
#include "shape_torus_fixture.h"

static void torus_coeffs(const double o[3], const double d[3], const double *params, double *c)
{
    double a = params[0], b = params[1];
    double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double e = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - a * a - b * b;
    double f = o[0] * d[0] + o[1] * d[1] + o[2] * d[2];
    double four_a2 = 4.0 * a * a;
    c[0] = e * e - four_a2 * (b * b - o[1] * o[1]);
    c[1] = 4.0 * f * e + 2.0 * four_a2 * o[1] * d[1];
    c[2] = 2.0 * dd * e + 4.0 * f * f + four_a2 * d[1] * d[1];
    c[3] = 4.0 * dd * f;
    c[4] = dd * dd;
}

static double torus_value(const double p[3], const double *params)
{
    double a = params[0], b = params[1];
    double s = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    return s * s - 2.0 * (a * a + b * b) * s + 4.0 * a * a * p[1] * p[1] + (a * a - b * b) * (a * a - b * b);
}

static void torus_gradient(const double p[3], const double *params, double g[3])
{
    double a = params[0], b = params[1];
    double s = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - a * a - b * b;
    g[0] = 4.0 * p[0] * s;
    g[1] = 4.0 * p[1] * (s + 2.0 * a * a);
    g[2] = 4.0 * p[2] * s;
}

static int torus_bounds(const double *params, double box[6])
{
    double a = params[0], b = params[1];
    box[0] = box[2] = -(a + b);
    box[3] = box[5] = a + b;
    box[1] = -b;
    box[4] = b;
    return 1;
}

const ig_shape shape_torus_fixture = {"torus_fixture", 4, 2, torus_coeffs, torus_value, torus_gradient,
                                      torus_bounds,    0};
