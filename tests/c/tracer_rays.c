/* Ray-level tests of the tracer against analytic answers. Built by tests/test_tracer_c.py with
 * -fsanitize=address,undefined and linked with the runtime and the checked-in generated shapes
 * sphere, torus_z and piriform. Prints one line per check group; exit status = number of failures. */
#include "tracer_internal.h"
#include "sphere.h"
#include "torus_z.h"
#include "piriform.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#ifndef M_SQRT1_2
#define M_SQRT1_2 0.70710678118654752440
#endif

static int failures = 0;

#define CHECK(cond, ...)                                                                                               \
    do {                                                                                                               \
        if (!(cond)) {                                                                                                 \
            ++failures;                                                                                                \
            printf("FAIL %s:%d: ", __FILE__, __LINE__);                                                                \
            printf(__VA_ARGS__);                                                                                       \
            printf("\n");                                                                                              \
        }                                                                                                              \
    } while (0)

static const double IDENTITY[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

static double urand(unsigned long long *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

static int add_matte(rt_scene *s)
{
    double m[RT_MATERIAL_DOUBLES] = {0.8, 0.8, 0.8, 0, 0, 0, 0, 0.1, 0.9, 0, 10, 0, 0, 1.5, 0, 0, 0, 0, 0};
    return rt_scene_add_material(s, m);
}

static void translate_scale(double m[12], double tx, double ty, double tz, double k)
{
    memset(m, 0, 12 * sizeof(double));
    m[0] = m[5] = m[10] = k;
    m[3] = tx;
    m[7] = ty;
    m[11] = tz;
}

/* ---------------------------------------------------------------- spheres */
static void test_sphere_distances(void)
{
    rt_scene *s = rt_scene_new();
    double m[12], r = 2.0, one = 1.0, worst = 0.0;
    int mat = add_matte(s), i, nmiss = 0;
    rt_hit h;
    unsigned long long seed = 1;
    /* sphere r = 2 centred at (1, 2, 3), as params r = 2 with a translation ... */
    translate_scale(m, 1, 2, 3, 1.0);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &r, 1, m, mat));
    /* ... and the unit sphere scaled by 0.5 about (10, 0, 0): radius 0.5 */
    translate_scale(m, 10, 0, 0, 0.5);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, m, mat));
    CHECK(rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
    {
        double o[3] = {1, 2, -10}, d[3] = {0, 0, 1}, d2[3] = {0, 0, 0.5};
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1, "axis ray misses");
        CHECK(fabs(h.t - 11.0) < 1e-12, "t = %.17g, want 11", h.t);
        CHECK(fabs(h.n[2] + 1.0) < 1e-12 && h.entering == 1, "normal/entering wrong");
        CHECK(rt_scene_intersect(s, o, d2, 0, INFINITY, &h) == 1 && fabs(h.t - 22.0) < 1e-11,
              "non-unit direction: t = %.17g, want 22", h.t);
        o[2] = 3.0; /* from the centre: leaves at t = 2 */
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1 && fabs(h.t - 2.0) < 1e-12 && h.entering == 0,
              "from inside: t = %.17g entering %d", h.t, h.entering);
    }
    {
        double o[3] = {10, 0.3, 5}, d[3] = {0, 0, -1};
        double want = 5.0 - sqrt(0.25 - 0.09);
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1 && fabs(h.t - want) < 1e-12,
              "scaled sphere: t = %.17g want %.17g", h.t, want);
        CHECK(fabs(h.n[1] - 0.6) < 1e-12 && fabs(h.n[2] - sqrt(0.64)) < 1e-12, "scaled sphere normal");
    }
    /* random rays against the analytic closest root (both spheres) */
    for (i = 0; i < 20000; ++i) {
        double o[3], d[3], best = INFINITY;
        double cs[2][4] = {{1, 2, 3, 2.0}, {10, 0, 0, 0.5}};
        int k, got;
        for (k = 0; k < 3; ++k) {
            o[k] = 30.0 * urand(&seed) - 10.0;
            d[k] = 2.0 * urand(&seed) - 1.0;
        }
        for (k = 0; k < 2; ++k) {
            long double oc[3], a = 0, b = 0, c = 0, disc;
            int j;
            for (j = 0; j < 3; ++j) {
                oc[j] = (long double)o[j] - cs[k][j];
                a += (long double)d[j] * d[j];
                b += 2.0L * oc[j] * d[j];
                c += oc[j] * oc[j];
            }
            c -= (long double)cs[k][3] * cs[k][3];
            disc = b * b - 4 * a * c;
            if (disc > 0) {
                long double q = -0.5L * (b + (b >= 0 ? sqrtl(disc) : -sqrtl(disc)));
                long double t1 = q / a, t2 = c / q, lo = t1 < t2 ? t1 : t2, hi = t1 < t2 ? t2 : t1;
                double t = lo > 0 ? (double)lo : (hi > 0 ? (double)hi : INFINITY);
                if (t < best)
                    best = t;
            }
        }
        got = rt_scene_intersect(s, o, d, 0, INFINITY, &h);
        if (isfinite(best) != (got == 1)) {
            ++nmiss;
        } else if (got) {
            double e = fabs(h.t - best) / fmax(1.0, best);
            if (e > worst)
                worst = e;
        }
    }
    CHECK(nmiss == 0, "%d random rays disagree on hit/miss", nmiss);
    CHECK(worst < 1e-12, "worst relative t error %.3g", worst);
    printf("sphere: 20000 random rays, hit/miss disagreements %d, worst relative t error %.3g\n", nmiss, worst);
    rt_scene_free(s);
}

/* ---------------------------------------------------------------- optics */
static void test_optics(void)
{
    double n[3] = {0, 1, 0}, worst_snell = 0.0, worst_plane = 0.0;
    int i, tir_wrong = 0;
    unsigned long long seed = 7;
    double etas[4] = {1.0 / 1.5, 1.5, 1.0 / 1.33, 2.4};
    for (i = 0; i < 40000; ++i) {
        double eta = etas[i % 4], th = 0.5 * M_PI * urand(&seed), ph = 2 * M_PI * urand(&seed);
        double d[3] = {sin(th) * cos(ph), -cos(th), sin(th) * sin(ph)}, t[3], crit;
        int ok = rt_refract(d, n, eta, t);
        crit = eta > 1.0 ? asin(1.0 / eta) : M_PI;
        if ((th > crit + 1e-12 && ok) || (th < crit - 1e-12 && !ok))
            ++tir_wrong;
        if (ok) {
            double st = sqrt(t[0] * t[0] + t[2] * t[2]);
            double e = fabs(eta * sin(th) - st);
            /* coplanar: t lies in the plane of d and n */
            double cx[3] = {d[1] * n[2] - d[2] * n[1], d[2] * n[0] - d[0] * n[2], d[0] * n[1] - d[1] * n[0]};
            double pe = fabs(rt_dot(cx, t));
            if (e > worst_snell)
                worst_snell = e;
            if (pe > worst_plane)
                worst_plane = pe;
            CHECK(t[1] < 0.0 || th > 1.5707, "refracted ray must go through the surface");
        }
    }
    CHECK(worst_snell < 1e-14, "Snell residual %.3g", worst_snell);
    CHECK(worst_plane < 1e-14, "coplanarity residual %.3g", worst_plane);
    CHECK(tir_wrong == 0, "%d rays on the wrong side of the critical angle", tir_wrong);
    printf("snell: 40000 rays, worst |eta sin(i) - sin(t)| %.3g, coplanarity %.3g, TIR misclassified %d\n", worst_snell,
           worst_plane, tir_wrong);
    {
        double d[3] = {sin(0.9), -cos(0.9), 0}, t[3];
        /* 0.9 rad > asin(1/1.5) = 0.7297: total internal reflection going from glass to air */
        CHECK(rt_refract(d, n, 1.5, t) == 0, "TIR expected at 0.9 rad");
        CHECK(rt_fresnel(cos(0.9), 1.5) == 1.0, "Fresnel must be 1 under TIR");
        d[0] = sin(0.72);
        d[1] = -cos(0.72);
        CHECK(rt_refract(d, n, 1.5, t) == 1, "no TIR expected at 0.72 rad");
    }
    {
        double r0 = rt_fresnel(1.0, 1.0 / 1.5), want = 0.04, brew = atan(1.5), rb, rs;
        double ct = cos(asin(sin(brew) / 1.5));
        CHECK(fabs(r0 - want) < 1e-15, "normal incidence R = %.17g", r0);
        /* at Brewster's angle only the s-polarised part reflects: R = rs^2 / 2 */
        rs = (cos(brew) - 1.5 * ct) / (cos(brew) + 1.5 * ct);
        rb = rt_fresnel(cos(brew), 1.0 / 1.5);
        CHECK(fabs(rb - 0.5 * rs * rs) < 1e-15, "Brewster R = %.17g want %.17g", rb, 0.5 * rs * rs);
        CHECK(rt_fresnel(1e-9, 1.0 / 1.5) > 0.999, "grazing incidence must reflect almost all");
        printf("fresnel: R(0) = %.17g, R(Brewster) = %.17g (want %.17g)\n", r0, rb, 0.5 * rs * rs);
    }
    {
        double d[3] = {1, -1, 0}, r[3];
        rt_reflect(d, n, r);
        CHECK(fabs(r[0] - M_SQRT1_2) < 1e-15 && fabs(r[1] - M_SQRT1_2) < 1e-15, "mirror reflection");
    }
}

/* ---------------------------------------------------------------- CSG */

/* A hand-written shape: the cylinder x^2 + z^2 = 1 whose bounds cut it to -1 <= y <= 1. */
static void cyl_coeffs(const double o[3], const double d[3], const double *p, double *c)
{
    (void)p;
    c[0] = o[0] * o[0] + o[2] * o[2] - 1.0;
    c[1] = 2.0 * (o[0] * d[0] + o[2] * d[2]);
    c[2] = d[0] * d[0] + d[2] * d[2];
}
static double cyl_value(const double q[3], const double *p)
{
    (void)p;
    return q[0] * q[0] + q[2] * q[2] - 1.0;
}
static void cyl_gradient(const double q[3], const double *p, double g[3])
{
    (void)p;
    g[0] = 2.0 * q[0];
    g[1] = 0.0;
    g[2] = 2.0 * q[2];
}
static int cyl_bounds(const double *p, double box[6])
{
    (void)p;
    box[0] = -1.0;
    box[1] = -1.0;
    box[2] = -1.0;
    box[3] = 1.0;
    box[4] = 1.0;
    box[5] = 1.0;
    return 1;
}
static const ig_shape capped_cylinder = {"capped_cylinder", 2, 0, cyl_coeffs, cyl_value, cyl_gradient, cyl_bounds};
static void test_csg(void)
{
    rt_scene *s = rt_scene_new();
    double one = 1.0, mB[12], tin[8], tout[8], tp[2] = {1.0, 0.25};
    int lin[8], lout[8], mat = add_matte(s), A, B, U, I, D, T, S, TD, n;
    rt_hit h;
    translate_scale(mB, 1, 0, 0, 1.0);
    A = rt_scene_add_leaf(s, &sphere_shape, &one, 1, IDENTITY, mat);
    B = rt_scene_add_leaf(s, &sphere_shape, &one, 1, mB, mat);
    U = rt_scene_add_csg(s, RT_UNION, A, B, mat);
    I = rt_scene_add_csg(s, RT_INTERSECTION, A, B, mat);
    D = rt_scene_add_csg(s, RT_DIFFERENCE, A, B, mat);
    T = rt_scene_add_leaf(s, &torus_z_shape, tp, 2, IDENTITY, mat);
    S = rt_scene_add_leaf(s, &sphere_shape, &one, 1, IDENTITY, mat);
    TD = rt_scene_add_csg(s, RT_DIFFERENCE, T, S, mat);
    rt_scene_add_object(s, D);
    {
        /* inside CSG a leaf is {f < 0} cut by its box: the box faces close the cylinder */
        double mf[12], mc[12];
        int C, F, CU;
        translate_scale(mf, 0, 50, 0, 0.1);
        translate_scale(mc, 0, 0, 20, 1.0); /* away from the spheres below */
        C = rt_scene_add_leaf(s, &capped_cylinder, NULL, 0, mc, mat);
        F = rt_scene_add_leaf(s, &sphere_shape, &one, 1, mf, mat);
        CU = rt_scene_add_csg(s, RT_UNION, C, F, mat);
        rt_scene_add_object(s, CU);
    }
    CHECK(rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
    {
        double o[3] = {0.3, -5, 20.2}, d[3] = {0, 1, 0};
        rt_hit hc;
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &hc) == 1 && fabs(hc.t - 4.0) < 1e-12 && hc.face == -2 &&
                  hc.entering && fabs(hc.n[1] + 1.0) < 1e-12,
              "capped cylinder bottom face: t %g face %d n (%g %g %g)", hc.t, hc.face, hc.n[0], hc.n[1], hc.n[2]);
        o[1] = 0.0; /* from inside: leaves through the top face */
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &hc) == 1 && fabs(hc.t - 1.0) < 1e-12 && hc.face == 2 &&
                  !hc.entering && fabs(hc.n[1] - 1.0) < 1e-12,
              "capped cylinder top face from inside: t %g face %d", hc.t, hc.face);
        /* the side is the surface f = 0, even where it touches the box face x = -1 */
        o[0] = -5.0;
        o[1] = 0.5;
        o[2] = 20.0;
        d[0] = 1.0;
        d[1] = 0.0;
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &hc) == 1 && fabs(hc.t - 4.0) < 1e-12 && hc.face == 0 &&
                  fabs(hc.n[0] + 1.0) < 1e-12,
              "capped cylinder side: t %g face %d", hc.t, hc.face);
    }
    {
        double o[3] = {-5, 0, 0}, d[3] = {1, 0, 0};
        n = rt_node_spans(s, D, o, d, 0, INFINITY, tin, tout, lin, lout, 8);
        CHECK(n == 1 && fabs(tin[0] - 4) < 1e-12 && fabs(tout[0] - 5) < 1e-12 && lin[0] == A && lout[0] == B,
              "A - B: %d spans [%g, %g] leaves %d %d", n, tin[0], tout[0], lin[0], lout[0]);
        n = rt_node_spans(s, U, o, d, 0, INFINITY, tin, tout, lin, lout, 8);
        CHECK(n == 1 && fabs(tin[0] - 4) < 1e-12 && fabs(tout[0] - 7) < 1e-12 && lin[0] == A && lout[0] == B,
              "A | B: %d spans", n);
        n = rt_node_spans(s, I, o, d, 0, INFINITY, tin, tout, lin, lout, 8);
        CHECK(n == 1 && fabs(tin[0] - 5) < 1e-12 && fabs(tout[0] - 6) < 1e-12 && lin[0] == B && lout[0] == A,
              "A & B: %d spans", n);
        printf("csg spheres along x: A-B, A|B, A&B spans as expected\n");
        /* starting inside A - B: the interval is open at the start */
        o[0] = -0.5;
        n = rt_node_spans(s, D, o, d, 0, INFINITY, tin, tout, lin, lout, 8);
        CHECK(n == 1 && tin[0] == 0.0 && lin[0] == -1 && fabs(tout[0] - 0.5) < 1e-12, "open start");
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &h) && fabs(h.t - 0.5) < 1e-12 && !h.entering &&
                  h.n[0] > 0.999999,
              "leaving A - B through B's (flipped) surface: t %g n (%g %g %g)", h.t, h.n[0], h.n[1], h.n[2]);
    }
    {
        /* from +x: enter A - B through B's surface at x = 0; B's outward normal there is -x, flipped +x */
        double o[3] = {5, 0, 0}, d[3] = {-1, 0, 0};
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1, "A - B from +x misses");
        CHECK(fabs(h.t - 5.0) < 1e-12 && h.leaf == B && h.entering && fabs(h.n[0] - 1.0) < 1e-12,
              "A - B from +x: t %g leaf %d entering %d n (%g %g %g)", h.t, h.leaf, h.entering, h.n[0], h.n[1], h.n[2]);
    }
    {
        /* tangent: y = 1 grazes both spheres (double roots), so there is no inside anywhere */
        double o[3] = {-5, 1, 0}, d[3] = {1, 0, 0};
        n = rt_node_spans(s, U, o, d, 0, INFINITY, tin, tout, lin, lout, 8);
        CHECK(n == 0, "tangent ray gives %d spans", n);
        o[1] = 1.0 - 1e-6; /* just inside: two thin spans which the union merges into one */
        n = rt_node_spans(s, U, o, d, 0, INFINITY, tin, tout, lin, lout, 8);
        CHECK(n == 2, "near-tangent ray gives %d spans, want 2", n);
    }
    {
        /* a non-convex leaf: torus (R = 1, r = 0.25) minus the unit sphere, along x */
        double o[3] = {-5, 0, 0}, d[3] = {1, 0, 0};
        n = rt_node_spans(s, TD, o, d, 0, INFINITY, tin, tout, lin, lout, 8);
        CHECK(n == 2 && fabs(tin[0] - 3.75) < 1e-12 && fabs(tout[0] - 4.0) < 1e-12 && fabs(tin[1] - 6.0) < 1e-12 &&
                  fabs(tout[1] - 6.25) < 1e-12 && lout[0] == S && lin[1] == S,
              "torus - sphere: %d spans", n);
        printf("csg torus - sphere: [%g, %g] [%g, %g]\n", tin[0], tout[0], tin[1], tout[1]);
    }
    rt_scene_free(s);
}

/* ---------------------------------------------------------------- transforms */
static void rot_axis(const double axis[3], double ang, double R[9])
{
    double c = cos(ang), sn = sin(ang), l = sqrt(rt_dot(axis, axis)), x = axis[0] / l, y = axis[1] / l, z = axis[2] / l;
    R[0] = c + x * x * (1 - c);
    R[1] = x * y * (1 - c) - z * sn;
    R[2] = x * z * (1 - c) + y * sn;
    R[3] = y * x * (1 - c) + z * sn;
    R[4] = c + y * y * (1 - c);
    R[5] = y * z * (1 - c) - x * sn;
    R[6] = z * x * (1 - c) - y * sn;
    R[7] = z * y * (1 - c) + x * sn;
    R[8] = c + z * z * (1 - c);
}

static void test_transformed_torus(void)
{
    /* M = T R S; the inverse is composed independently as S^-1 R^T (p - T) */
    double axis[3] = {1, 2, -0.5}, R[9], S[3] = {2.0, 0.7, 1.3}, T[3] = {3, -1, 4}, M[12], tp[2] = {1.0, 0.3};
    double worst = 0.0, worst_n = 0.0;
    int i, j, mat, leaf, disagree = 0, hits = 0;
    unsigned long long seed = 11;
    rt_scene *s = rt_scene_new();
    rt_hit h;
    rot_axis(axis, 0.8, R);
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j)
            M[4 * i + j] = R[3 * i + j] * S[j];
        M[4 * i + 3] = T[i];
    }
    mat = add_matte(s);
    leaf = rt_scene_add_leaf(s, &torus_z_shape, tp, 2, M, mat);
    rt_scene_add_object(s, leaf);
    CHECK(rt_scene_commit(s) == 0, "commit");
    for (i = 0; i < 20000; ++i) {
        double o[3], d[3], oo[3], od[3], po[3], c[5], roots[IG_MAX_DEGREE], first = INFINITY;
        int k, nr, got;
        for (k = 0; k < 3; ++k) {
            o[k] = T[k] + 8.0 * urand(&seed) - 4.0;
            d[k] = T[k] + 1.2 * (2.0 * urand(&seed) - 1.0) - o[k];
        }
        for (k = 0; k < 3; ++k)
            po[k] = o[k] - T[k];
        for (k = 0; k < 3; ++k) {
            oo[k] = (R[k] * po[0] + R[3 + k] * po[1] + R[6 + k] * po[2]) / S[k];
            od[k] = (R[k] * d[0] + R[3 + k] * d[1] + R[6 + k] * d[2]) / S[k];
        }
        /* object-space roots of the torus polynomial, straight from the coefficients */
        torus_z_coeffs(oo, od, tp, c);
        nr = ig_real_roots(c, 4, 0.0, 1e3, IG_ROOTS_STURM, roots);
        for (k = 0; k < nr; ++k)
            if (roots[k] > 0.0) {
                first = roots[k];
                break;
            }
        got = rt_scene_intersect(s, o, d, 0, INFINITY, &h);
        if (got != isfinite(first)) {
            ++disagree;
            continue;
        }
        if (!got)
            continue;
        ++hits;
        if (fabs(h.t - first) / fmax(1.0, first) > worst)
            worst = fabs(h.t - first) / fmax(1.0, first);
        /* the world normal must be perpendicular to M x (object tangent vectors) */
        {
            double g[3], t1[3], t2[3], w1[3], w2[3], p[3];
            for (k = 0; k < 3; ++k)
                p[k] = oo[k] + h.t * od[k];
            torus_z_gradient(p, tp, g);
            /* two tangents: g x e, g x (g x e) */
            {
                double e[3] = {0.3, -0.5, 0.8};
                t1[0] = g[1] * e[2] - g[2] * e[1];
                t1[1] = g[2] * e[0] - g[0] * e[2];
                t1[2] = g[0] * e[1] - g[1] * e[0];
                t2[0] = g[1] * t1[2] - g[2] * t1[1];
                t2[1] = g[2] * t1[0] - g[0] * t1[2];
                t2[2] = g[0] * t1[1] - g[1] * t1[0];
            }
            rt_xform_vector(M, t1, w1);
            rt_xform_vector(M, t2, w2);
            {
                double e1 = fabs(rt_dot(w1, h.n)) / sqrt(rt_dot(w1, w1));
                double e2 = fabs(rt_dot(w2, h.n)) / sqrt(rt_dot(w2, w2));
                if (e1 > worst_n)
                    worst_n = e1;
                if (e2 > worst_n)
                    worst_n = e2;
            }
        }
    }
    CHECK(disagree == 0, "%d rays disagree with the inverse-transformed ray", disagree);
    CHECK(worst < 1e-9, "worst relative t difference %.3g", worst);
    CHECK(worst_n < 1e-9, "normal not perpendicular to transformed tangents: %.3g", worst_n);
    printf("transformed torus: 20000 rays (%d hits), hit/miss disagreements %d, worst relative t diff %.3g, "
           "normal.tangent %.3g\n",
           hits, disagree, worst, worst_n);
    rt_scene_free(s);
}

static void test_piriform_basis(void)
{
    /* the paper's form: position P and axis vectors u, v, w as the columns of the object -> world map */
    double P[3] = {2, -1, 5}, u[3] = {0, 0, 3}, v[3] = {0, 2, 0}, w[3] = {-1.5, 0, 0}, M[12];
    int k, mat, leaf;
    rt_scene *s = rt_scene_new();
    rt_hit h;
    for (k = 0; k < 3; ++k) {
        M[4 * k] = u[k];
        M[4 * k + 1] = v[k];
        M[4 * k + 2] = w[k];
        M[4 * k + 3] = P[k];
    }
    mat = add_matte(s);
    leaf = rt_scene_add_leaf(s, &piriform_shape, NULL, 0, M, mat);
    rt_scene_add_object(s, leaf);
    CHECK(rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
    {
        /* along the u axis from P - 3u: object ray (-3, 0, 0) + t (1, 0, 0); f = x^3 (x - 1): the cusp at t = 3
         * (a triple root), the tip at t = 4 */
        double o[3], d[3];
        for (k = 0; k < 3; ++k) {
            o[k] = P[k] - 3 * u[k];
            d[k] = u[k];
        }
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1, "piriform axis ray misses");
        CHECK(fabs(h.t - 3.0) < 1e-4, "cusp at t = %.17g, want 3", h.t);
        CHECK(isfinite(h.n[0]) && isfinite(h.n[1]) && isfinite(h.n[2]) && fabs(rt_dot(h.n, h.n) - 1) < 1e-12,
              "cusp normal not finite/unit");
        printf("piriform cusp: t = %.12g (want 3), singular %d, normal (%g %g %g)\n", h.t, h.singular, h.n[0], h.n[1],
               h.n[2]);
        CHECK(rt_scene_intersect(s, o, d, 3.5, INFINITY, &h) == 1 && fabs(h.t - 4.0) < 1e-12,
              "tip at t = %.17g, want 4", h.t);
    }
    {
        /* through object point (0.5, y, 0) along v: y^2 = 0.0625 gives t = 1.75 and 2.25 */
        double o[3], d[3], g[3] = {-0.25, -0.5, 0}, want[3], l;
        for (k = 0; k < 3; ++k) {
            o[k] = P[k] + 0.5 * u[k] - 2 * v[k];
            d[k] = v[k];
        }
        CHECK(rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1 && fabs(h.t - 1.75) < 1e-12, "t = %.17g want 1.75",
              h.t);
        /* object gradient (-0.25, -0.5, 0) maps to g_x u/|u|^2 + g_y v/|v|^2 + g_z w/|w|^2 */
        for (k = 0; k < 3; ++k)
            want[k] = g[0] * u[k] / 9.0 + g[1] * v[k] / 4.0 + g[2] * w[k] / 2.25;
        l = sqrt(rt_dot(want, want));
        for (k = 0; k < 3; ++k)
            CHECK(fabs(h.n[k] - want[k] / l) < 1e-12, "piriform normal[%d]", k);
        CHECK(rt_scene_intersect(s, o, d, 1.8, INFINITY, &h) == 1 && fabs(h.t - 2.25) < 1e-12, "second root");
    }
    rt_scene_free(s);
}

/* ---------------------------------------------------------------- an unbounded plane and a shadow */
static void test_unbounded_and_shading(void)
{
    /* Shading against hand-computed values: a point light, an occluder, the background. (Unbounded planes
     * are exercised by the Python render tests, which generate a plane shape.) */
    rt_scene *s = rt_scene_new();
    double one = 1.0, m[12], eye[3] = {0, 0, 10}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0}, bg[3] = {0.1, 0.2, 0.3};
    double lp[3] = {0, 0, 10}, lc[3] = {1, 1, 1}, rgb[3], st[RT_NSTATS] = {0, 0, 0};
    int mat = add_matte(s);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, IDENTITY, mat));
    translate_scale(m, 0, 0, 3, 0.2); /* small occluder between the light and the sphere's front */
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, m, mat));
    rt_scene_add_light(s, lp, lc);
    rt_scene_set_camera(s, eye, at, up, 30);
    rt_scene_set_background(s, bg);
    CHECK(rt_scene_commit(s) == 0, "commit");
    {
        double o[3] = {0, 5, 10}, d[3] = {0, 0, -1};
        rt_trace_ray(s, o, d, 4, rgb, st);
        CHECK(rgb[0] == 0.1 && rgb[1] == 0.2 && rgb[2] == 0.3, "a miss shows the background");
    }
    {
        /* lit point: (0.6, 0, 0.8) seen from the light direction; diffuse 0.9 * 0.8 * n.l + ambient 0.08 */
        double o[3] = {0.6, 0, 10}, d[3] = {0, 0, -1}, L[3] = {-0.6, 0, 9.2}, nl;
        nl = (0.6 * L[0] + 0.8 * L[2]) / sqrt(rt_dot(L, L));
        rt_trace_ray(s, o, d, 4, rgb, st);
        CHECK(fabs(rgb[0] - (0.08 + 0.72 * nl)) < 1e-9, "lit colour %.17g want %.17g", rgb[0], 0.08 + 0.72 * nl);
    }
    {
        /* the point (0, 0, 1) is shadowed by the occluder at z = 3: ambient only */
        double o[3] = {0, 0, 10}, d[3] = {0, 0, -1};
        rt_trace_ray(s, o, d, 4, rgb, st);
        /* the camera ray hits the occluder first; shoot from just in front of the sphere instead */
        o[2] = 2.0;
        rt_trace_ray(s, o, d, 4, rgb, st);
        CHECK(fabs(rgb[0] - 0.08) < 1e-12, "shadowed colour %.17g want ambient 0.08", rgb[0]);
    }
    CHECK(st[RT_RAYS_PRIMARY] == 4 && st[RT_RAYS_SHADOW] >= 2, "ray counts %g %g", st[0], st[1]);
    rt_scene_free(s);
}

/* ---------------------------------------------------------------- glass: Beer-Lambert, CSG boundaries, shadows */
static void glass_material(double m[RT_MATERIAL_DOUBLES], double ior, double tr, double s0, double s1, double s2)
{
    memset(m, 0, RT_MATERIAL_DOUBLES * sizeof(double));
    m[0] = m[1] = m[2] = 1.0;
    m[12] = tr; /* transparency */
    m[13] = ior;
    m[14] = s0; /* absorption */
    m[15] = s1;
    m[16] = s2;
}

static void test_glass(void)
{
    double one = 1.0, half = 0.5, bg[3] = {1.0, 0.8, 0.6}, rgb[3], sigma[3] = {0.5, 1.0, 2.0}, m[RT_MATERIAL_DOUBLES];
    double eye[3] = {0, 0, 10}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0}, half_m[12];
    int k, a, g;
    {
        /* A solid glass ball (n = 1.5) along its diameter, recursion depth 2: the front face reflects F of the
         * background; the rest crosses 2 units of glass, and F of it reflects inside (and ends at the depth
         * limit, black) while 1 - F leaves: F bg + (1 - F)^2 exp(-2 sigma) bg, F = ((1.5 - 1)/(1.5 + 1))^2. */
        rt_scene *s = rt_scene_new();
        double F = 0.04;
        glass_material(m, 1.5, 1.0, sigma[0], sigma[1], sigma[2]);
        g = rt_scene_add_material(s, m);
        rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, IDENTITY, g));
        rt_scene_set_camera(s, eye, at, up, 30);
        rt_scene_set_background(s, bg);
        CHECK(rt_scene_commit(s) == 0, "commit");
        {
            double o[3] = {0, 0, 5}, d[3] = {0, 0, -1};
            rt_trace_ray(s, o, d, 2, rgb, NULL);
            for (a = 0; a < 3; ++a) {
                double want = F * bg[a] + (1 - F) * (1 - F) * exp(-2 * sigma[a]) * bg[a];
                CHECK(fabs(rgb[a] - want) < 1e-12, "Beer-Lambert channel %d: %.17g want %.17g", a, rgb[a], want);
            }
            printf("glass ball, depth 2: (%.6f %.6f %.6f) = F bg + (1-F)^2 exp(-2 sigma) bg\n", rgb[0], rgb[1], rgb[2]);
        }
        {
            /* From inside the ball (no absorption): a chord meeting the surface at 60 degrees is beyond the
             * critical angle asin(1/1.5) = 41.8 degrees, so every bounce is a total internal reflection, the
             * ray never leaves and the depth limit ends it in black. At 30 degrees the surface lets
             * (1 - F(30 deg)) of the background through, plus what the reflections bring. */
            rt_scene *s2 = rt_scene_new();
            double o[3] = {0, 0, 0}, d60[3], d30[3], Ft, c60[3], c30[3];
            glass_material(m, 1.5, 1.0, 0, 0, 0);
            g = rt_scene_add_material(s2, m);
            rt_scene_add_object(s2, rt_scene_add_leaf(s2, &sphere_shape, &one, 1, IDENTITY, g));
            rt_scene_set_background(s2, bg);
            CHECK(rt_scene_commit(s2) == 0, "commit");
            /* start at (0, -sin a, 0)... a chord from a point at distance sin(a) from the centre, heading along
             * x, meets the sphere with incidence angle a */
            o[1] = -sin(60.0 * M_PI / 180.0);
            d60[0] = 1;
            d60[1] = 0;
            d60[2] = 0;
            rt_trace_ray(s2, o, d60, 12, c60, NULL);
            o[1] = -sin(30.0 * M_PI / 180.0);
            d30[0] = 1;
            d30[1] = 0;
            d30[2] = 0;
            rt_trace_ray(s2, o, d30, 12, c30, NULL);
            Ft = rt_fresnel(cos(30.0 * M_PI / 180.0), 1.5);
            CHECK(c60[0] == 0.0 && c60[1] == 0.0 && c60[2] == 0.0, "TIR must trap the ray: (%g %g %g)", c60[0], c60[1],
                  c60[2]);
            for (a = 0; a < 3; ++a)
                CHECK(c30[a] >= (1 - Ft) * bg[a] - 1e-12 && c30[a] <= bg[a] + 1e-12, "30 deg: %g (F %g)", c30[a], Ft);
            printf("inside the ball: 60 deg -> (%g %g %g) (trapped), 30 deg -> %.6f >= (1 - F) bg = %.6f\n", c60[0],
                   c60[1], c60[2], c30[0], (1 - Ft) * bg[0]);
            rt_scene_free(s2);
        }
        rt_scene_free(s);
    }
    {
        /* An index-matched (n = 1, so F = 0 and rays go straight) absorbing shell: sphere r = 1 minus sphere
         * r = 0.5. Every ray must cross all four CSG boundaries and absorb over exactly the glass path:
         * 2 sqrt(1 - h^2) - 2 sqrt(0.25 - h^2) at height h < 0.5, 2 sqrt(1 - h^2) above. */
        rt_scene *s = rt_scene_new();
        double worst = 0.0;
        int A, B;
        glass_material(m, 1.0, 1.0, sigma[0], sigma[1], sigma[2]);
        g = rt_scene_add_material(s, m);
        A = rt_scene_add_leaf(s, &sphere_shape, &one, 1, IDENTITY, g);
        translate_scale(half_m, 0, 0, 0, 1.0);
        B = rt_scene_add_leaf(s, &sphere_shape, &half, 1, half_m, g);
        rt_scene_add_object(s, rt_scene_add_csg(s, RT_DIFFERENCE, A, B, g));
        rt_scene_set_background(s, bg);
        CHECK(rt_scene_commit(s) == 0, "commit");
        for (k = 0; k < 200; ++k) {
            double h = 0.995 * k / 200.0, o[3] = {h, 0, 5}, d[3] = {0, 0, -1}, L;
            L = 2 * sqrt(1 - h * h) - (h < 0.5 ? 2 * sqrt(0.25 - h * h) : 0.0);
            rt_trace_ray(s, o, d, 8, rgb, NULL);
            for (a = 0; a < 3; ++a) {
                double e = fabs(rgb[a] - exp(-sigma[a] * L) * bg[a]);
                if (e > worst)
                    worst = e;
            }
        }
        /* each boundary moves the path by its error bound (~1e-12 here) */
        CHECK(worst < 1e-10, "absorbing CSG shell: worst error %.3g", worst);
        printf("index-matched CSG shell: 200 rays, worst |rgb - exp(-sigma L) bg| %.3g\n", worst);
        rt_scene_free(s);
    }
    {
        /* Shadow through glass: a clear ball (transparency 0.8, absorption sigma) between a light and a matte
         * sphere's top point; the light reaching it is 0.8 exp(-sigma * 2) (the shadow ray crosses the
         * diameter), so the colour is ambient + 0.8 exp(-2 sigma) * diffuse * n.l (n.l = 1). */
        rt_scene *s = rt_scene_new();
        double mm[RT_MATERIAL_DOUBLES] = {1, 1, 1, 0, 0, 0, 0, 0.1, 0.9, 0, 10, 0, 0, 1.5, 0, 0, 0, 0, 0};
        double big = 10.0, lp[3] = {0, 20, 0}, lc[3] = {1, 1, 1}, mg[12];
        int matte = rt_scene_add_material(s, mm);
        glass_material(m, 1.5, 0.8, sigma[0], sigma[1], sigma[2]);
        g = rt_scene_add_material(s, m);
        translate_scale(mg, 0, -10, 0, 1.0);
        rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &big, 1, mg, matte)); /* top point (0, 0, 0) */
        translate_scale(mg, 0, 5, 0, 1.0);
        rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, mg, g));
        rt_scene_add_light(s, lp, lc);
        CHECK(rt_scene_commit(s) == 0, "commit");
        {
            double o[3] = {0, 1e-3, 3}, d[3] = {0, -1e-3, -3}; /* reaches (0, 0, 0) from the side */
            rt_trace_ray(s, o, d, 4, rgb, NULL);
            for (a = 0; a < 3; ++a) {
                double want = 0.1 + 0.8 * exp(-2 * sigma[a]) * 0.9;
                CHECK(fabs(rgb[a] - want) < 1e-9, "shadow through glass channel %d: %.17g want %.17g", a, rgb[a], want);
            }
        }
        rt_scene_free(s);
    }
}

/* ---------------------------------------------------------------- the tracer's own shortcuts */

/* The plane y = 0 as a hand-written unbounded shape of degree 1. */
static void plane_coeffs(const double o[3], const double d[3], const double *p, double *c)
{
    (void)p;
    c[0] = o[1];
    c[1] = d[1];
}
static double plane_value(const double q[3], const double *p)
{
    (void)p;
    return q[1];
}
static void plane_gradient(const double q[3], const double *p, double g[3])
{
    (void)p;
    (void)q;
    g[0] = 0.0;
    g[1] = 1.0;
    g[2] = 0.0;
}
static int plane_bounds(const double *p, double box[6])
{
    (void)p;
    box[0] = box[1] = box[2] = -INFINITY;
    box[3] = box[4] = box[5] = INFINITY;
    return 0;
}
static const ig_shape plane_y = {"plane_y", 1, 0, plane_coeffs, plane_value, plane_gradient, plane_bounds};

static void test_shortcuts(void)
{
    /* A tilted plane, a transformed torus, an opaque sphere and a glass sphere. */
    double one = 1.0, tp[2] = {1.0, 0.3}, M[12], R[9], axis[3] = {0.3, 1, 0.2}, pl[12];
    double glass[RT_MATERIAL_DOUBLES] = {1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0.9, 1.5, 0, 0, 0, 0, 0};
    double checker[RT_MATERIAL_DOUBLES] = {1, 1, 1, 0, 0, 0, 0.7, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0};
    unsigned long long seed = 99;
    rt_scene *s = rt_scene_new();
    int i, k, mat = add_matte(s), gmat = rt_scene_add_material(s, glass), plane, torus, ball, gball;
    int same = 0, hits = 0, any_ok = 0, any_n = 0, any_behind = 0, self = 0, spawned = 0;
    rot_axis(axis, 0.4, R);
    for (i = 0; i < 3; ++i) {
        for (k = 0; k < 3; ++k) {
            M[4 * i + k] = 1.3 * R[3 * i + k];
            pl[4 * i + k] = R[3 * i + k];
        }
        M[4 * i + 3] = i == 1 ? 1.5 : 0.2;
        pl[4 * i + 3] = i == 1 ? -0.5 : 0.0;
    }
    plane = rt_scene_add_object(s, rt_scene_add_leaf(s, &plane_y, NULL, 0, pl, mat));
    torus = rt_scene_add_object(s, rt_scene_add_leaf(s, &torus_z_shape, tp, 2, M, mat));
    translate_scale(M, -2.5, 1, 0, 0.8);
    ball = rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, M, mat));
    translate_scale(M, 2.5, 1, 0.5, 0.8);
    gball = rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, M, gmat));
    CHECK(rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
    (void)torus;
    (void)ball;
    for (k = 0; k < 20000; ++k) {
        double o[3], d[3], q[3], L[3] = {0, 0, 0};
        rt_pending ph;
        rt_hit eager, lazy_hit;
        rt_hit_lazy lz;
        for (i = 0; i < 3; ++i) {
            o[i] = 12 * urand(&seed) - 6;
            d[i] = 2 * urand(&seed) - 1;
        }
        o[1] += 8.0;
        /* the error bound worked out later (rt_hit_error) is the one rt_scene_intersect gives at once */
        if (rt_scene_intersect(s, o, d, 0, INFINITY, &eager)) {
            ++hits;
            CHECK(rt_scene_closest(s, o, d, 0, INFINITY, RT_CLOSEST, -1, &ph), "closest disagrees with intersect");
            rt_finish_hit(s, &ph, o, d, &lazy_hit, &lz);
            rt_hit_error(s, &lazy_hit, &lz);
            rt_hit_error(s, &lazy_hit, &lz); /* a second call changes nothing */
            same += memcmp(&eager, &lazy_hit, sizeof eager) == 0;
            /* a ray leaving the plane never meets the plane again (why rays spawned there skip it) */
            if (eager.object == plane) {
                for (i = 0; i < 3; ++i)
                    L[i] = 2 * urand(&seed) - 1;
                rt_spawn_origin(&eager, L, q);
                ++spawned;
                if (rt_scene_closest(s, q, L, 0, INFINITY, RT_CLOSEST, -1, &ph) && ph.object == plane)
                    ++self;
                CHECK(rt_spawn_skip(s, &eager) == plane, "a plane hit must skip the plane");
            } else {
                CHECK(rt_spawn_skip(s, &eager) == -1, "only planes are skipped");
            }
        }
        /* RT_ANY_OPAQUE: an opaque hit whenever the segment holds one, else the closest (transparent) hit */
        {
            rt_pending pc, pa;
            int hc = rt_scene_closest(s, o, d, 0, 12.0, RT_CLOSEST, -1, &pc);
            int ha = rt_scene_closest(s, o, d, 0, 12.0, RT_ANY_OPAQUE, -1, &pa);
            int opaque_in_range = 0;
            double t = 0.0;
            /* walk the segment's hits in order to see whether any is opaque */
            while (rt_scene_closest(s, o, d, t, 12.0, RT_CLOSEST, -1, &ph)) {
                if (ph.object != gball) {
                    opaque_in_range = 1;
                    break;
                }
                t = ph.t;
            }
            if (hc) {
                ++any_n;
                if (opaque_in_range) {
                    any_ok += ha && pa.object != gball;
                    any_behind += pc.object == gball; /* the opaque hit lies behind the glass */
                } else {
                    any_ok += ha && pa.object == gball && pa.t == pc.t;
                }
            } else {
                CHECK(!ha, "RT_ANY_OPAQUE finds a hit where RT_CLOSEST finds none");
            }
        }
    }
    CHECK(hits > 5000 && same == hits, "lazy error bound: %d of %d hits identical", same, hits);
    CHECK(self == 0 && spawned > 1000, "rays leaving the plane met it again %d times of %d", self, spawned);
    CHECK(any_ok == any_n && any_n > 1000 && any_behind > 10,
          "RT_ANY_OPAQUE right on %d of %d segments (%d behind glass)", any_ok, any_n, any_behind);
    printf("shortcuts: %d hits, lazy error bound identical on %d; %d rays off the plane, %d met it again; any-opaque "
           "right on %d of %d segments, %d of them opaque behind glass\n",
           hits, same, spawned, self, any_ok, any_n, any_behind);
    rt_scene_free(s);

    {
        /* The checker (ambient 1, nothing else: the colour is the cell colour) against the fmod formula, at
         * cell indices of both signs and beyond 2^53, where every double is an even integer. */
        rt_scene *c = rt_scene_new();
        int cm = rt_scene_add_material(c, checker), wrong = 0, n = 0;
        double rgb[3];
        rt_scene_add_object(c, rt_scene_add_leaf(c, &plane_y, NULL, 0, IDENTITY, cm));
        CHECK(rt_scene_commit(c) == 0, "commit: %s", rt_scene_error(c));
        for (k = 0; k < 4000; ++k) {
            double mag = pow(10.0, 17.0 * urand(&seed)), x = (2 * urand(&seed) - 1) * mag,
                   z = (2 * urand(&seed) - 1) * mag, o[3], d[3] = {0, -1, 0}, sum = 0.0, want, q[3];
            o[0] = x;
            o[1] = 1.0;
            o[2] = z;
            rt_trace_ray(c, o, d, 0, rgb, NULL);
            q[0] = x / 0.7;
            q[1] = (0.0 - 1e-3 * 0.7 * 1.0) / 0.7;
            q[2] = z / 0.7;
            for (i = 0; i < 3; ++i)
                sum += fmod(fabs(floor(q[i])), 2.0);
            want = fmod(sum, 2.0) < 0.5 ? 1.0 : 0.0;
            ++n;
            wrong += rgb[0] != want;
        }
        CHECK(wrong == 0, "checker colour wrong at %d of %d points", wrong, n);
        rt_scene_free(c);
    }
}

int main(void)
{
    test_sphere_distances();
    test_optics();
    test_csg();
    test_transformed_torus();
    test_piriform_basis();
    test_unbounded_and_shading();
    test_glass();
    test_shortcuts();
    printf("%d failures\n", failures);
    return failures;
}
