/* Ray-level tests of the tracer against analytic answers: spheres, CSG, transforms (this file, with main)
 * and optics and shading (tracer_rays_optics.c). Built by tests/test_tracer_c.py with
 * -fsanitize=address,undefined and linked with the runtime and the checked-in generated shapes sphere,
 * torus_z and piriform. Prints one line per check group; exit status = number of failures. */
#include "tracer_rays.h"

int failures = 0;

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
    test_plane_path();
    printf("%d failures\n", failures);
    return failures;
}
