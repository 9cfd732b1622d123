/* Ray-level tests of the tracer against analytic answers, as named cases (tests/c/ctest.h): spheres, CSG,
 * transforms (this file, with main and the table of every case) and optics and shading (tracer_rays_optics.c).
 * Built by tests/test_tracer_c.py with -fsanitize=address,undefined and linked with the runtime and the
 * checked-in generated shapes sphere, torus_z and piriform; each case reported by name, what a case measures
 * printed before its verdict. */
#include "tracer_rays.h"

/* ---------------------------------------------------------------- spheres */

/* A sphere r = 2 centred at (1, 2, 3), as params r = 2 with a translation, and the unit sphere scaled by 0.5
 * about (10, 0, 0): radius 0.5. */
static rt_scene *two_spheres(ctest *t)
{
    rt_scene *s = rt_scene_new();
    double m[12], r = 2.0, one = 1.0;
    int mat = add_matte(s);
    translate_scale(m, 1, 2, 3, 1.0);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &r, 1, m, mat));
    translate_scale(m, 10, 0, 0, 0.5);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, m, mat));
    CHECKF(t, rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
    return s;
}

static void sphere_along_its_axis(ctest *t)
{
    rt_scene *s = two_spheres(t);
    double o[3] = {1, 2, -10}, d[3] = {0, 0, 1}, d2[3] = {0, 0, 0.5};
    rt_hit h;
    CHECKF(t, rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1, "axis ray misses");
    CHECKF(t, fabs(h.t - 11.0) < 1e-12, "t = %.17g, want 11", h.t);
    CHECKF(t, fabs(h.n[2] + 1.0) < 1e-12 && h.entering == 1, "normal/entering wrong");
    CHECKF(t, rt_scene_intersect(s, o, d2, 0, INFINITY, &h) == 1 && fabs(h.t - 22.0) < 1e-11,
           "non-unit direction: t = %.17g, want 22", h.t);
    o[2] = 3.0; /* from the centre: leaves at t = 2 */
    CHECKF(t, rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1 && fabs(h.t - 2.0) < 1e-12 && h.entering == 0,
           "from inside: t = %.17g entering %d", h.t, h.entering);
    rt_scene_free(s);
}

static void scaled_sphere(ctest *t)
{
    rt_scene *s = two_spheres(t);
    double o[3] = {10, 0.3, 5}, d[3] = {0, 0, -1};
    double want = 5.0 - sqrt(0.25 - 0.09);
    rt_hit h;
    CHECKF(t, rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1 && fabs(h.t - want) < 1e-12,
           "scaled sphere: t = %.17g want %.17g", h.t, want);
    CHECKF(t, fabs(h.n[1] - 0.6) < 1e-12 && fabs(h.n[2] - sqrt(0.64)) < 1e-12, "scaled sphere normal");
    rt_scene_free(s);
}

/* The closest root t > 0 of the two spheres along o + t d, in long double; INFINITY when the ray misses both. */
static double two_spheres_closest(const double o[3], const double d[3])
{
    const double cs[2][4] = {{1, 2, 3, 2.0}, {10, 0, 0, 0.5}};
    double best = INFINITY;
    for (int k = 0; k < 2; ++k) {
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
    return best;
}

/* random rays against the analytic closest root (both spheres) */
static void sphere_random_rays_against_the_closest_root(ctest *t)
{
    rt_scene *s = two_spheres(t);
    double worst = 0.0;
    int i, nmiss = 0;
    rt_hit h;
    unsigned long long seed = 1;
    for (i = 0; i < 20000; ++i) {
        double o[3], d[3], best;
        int k, got;
        for (k = 0; k < 3; ++k) {
            o[k] = 30.0 * urand(&seed) - 10.0;
            d[k] = 2.0 * urand(&seed) - 1.0;
        }
        best = two_spheres_closest(o, d);
        got = rt_scene_intersect(s, o, d, 0, INFINITY, &h);
        if (isfinite(best) != (got == 1)) {
            ++nmiss;
        } else if (got) {
            double e = fabs(h.t - best) / fmax(1.0, best);
            if (e > worst)
                worst = e;
        }
    }
    CHECKF(t, nmiss == 0, "%d random rays disagree on hit/miss", nmiss);
    CHECKF(t, worst < 1e-12, "worst relative t error %.3g", worst);
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
static const ig_shape capped_cylinder = {"capped_cylinder", 2, 0, cyl_coeffs, cyl_value, cyl_gradient, cyl_bounds, 0};

/* The CSG scene and its nodes: unit spheres A at 0 and B at (1, 0, 0), their union U, intersection I and
 * difference D (the one object of the three); the torus (R = 1, r = 0.25) minus the unit sphere S, TD; and, away
 * at z = 20, the capped cylinder united with a small sphere, an object. */
typedef struct {
    rt_scene *s;
    int A, B, U, I, D, S, TD;
} csg_nodes;

static csg_nodes csg_scene(ctest *t)
{
    csg_nodes c;
    double one = 1.0, mB[12], tp[2] = {1.0, 0.25}, mf[12], mc[12];
    int mat, T, C, F;
    c.s = rt_scene_new();
    mat = add_matte(c.s);
    translate_scale(mB, 1, 0, 0, 1.0);
    c.A = rt_scene_add_leaf(c.s, &sphere_shape, &one, 1, IDENTITY, mat);
    c.B = rt_scene_add_leaf(c.s, &sphere_shape, &one, 1, mB, mat);
    c.U = rt_scene_add_csg(c.s, RT_UNION, c.A, c.B, mat);
    c.I = rt_scene_add_csg(c.s, RT_INTERSECTION, c.A, c.B, mat);
    c.D = rt_scene_add_csg(c.s, RT_DIFFERENCE, c.A, c.B, mat);
    T = rt_scene_add_leaf(c.s, &torus_z_shape, tp, 2, IDENTITY, mat);
    c.S = rt_scene_add_leaf(c.s, &sphere_shape, &one, 1, IDENTITY, mat);
    c.TD = rt_scene_add_csg(c.s, RT_DIFFERENCE, T, c.S, mat);
    rt_scene_add_object(c.s, c.D);
    /* inside CSG a leaf is {f < 0} cut by its box: the box faces close the cylinder */
    translate_scale(mf, 0, 50, 0, 0.1);
    translate_scale(mc, 0, 0, 20, 1.0); /* away from the spheres */
    C = rt_scene_add_leaf(c.s, &capped_cylinder, NULL, 0, mc, mat);
    F = rt_scene_add_leaf(c.s, &sphere_shape, &one, 1, mf, mat);
    rt_scene_add_object(c.s, rt_scene_add_csg(c.s, RT_UNION, C, F, mat));
    CHECKF(t, rt_scene_commit(c.s) == 0, "commit: %s", rt_scene_error(c.s));
    return c;
}

static void capped_cylinder_closed_by_its_box_faces(ctest *t)
{
    csg_nodes c = csg_scene(t);
    double o[3] = {0.3, -5, 20.2}, d[3] = {0, 1, 0};
    rt_hit hc;
    CHECKF(t,
           rt_scene_intersect(c.s, o, d, 0, INFINITY, &hc) == 1 && fabs(hc.t - 4.0) < 1e-12 && hc.face == -2 &&
               hc.entering && fabs(hc.n[1] + 1.0) < 1e-12,
           "capped cylinder bottom face: t %g face %d n (%g %g %g)", hc.t, hc.face, hc.n[0], hc.n[1], hc.n[2]);
    o[1] = 0.0; /* from inside: leaves through the top face */
    CHECKF(t,
           rt_scene_intersect(c.s, o, d, 0, INFINITY, &hc) == 1 && fabs(hc.t - 1.0) < 1e-12 && hc.face == 2 &&
               !hc.entering && fabs(hc.n[1] - 1.0) < 1e-12,
           "capped cylinder top face from inside: t %g face %d", hc.t, hc.face);
    /* the side is the surface f = 0, even where it touches the box face x = -1 */
    o[0] = -5.0;
    o[1] = 0.5;
    o[2] = 20.0;
    d[0] = 1.0;
    d[1] = 0.0;
    CHECKF(t,
           rt_scene_intersect(c.s, o, d, 0, INFINITY, &hc) == 1 && fabs(hc.t - 4.0) < 1e-12 && hc.face == 0 &&
               fabs(hc.n[0] + 1.0) < 1e-12,
           "capped cylinder side: t %g face %d", hc.t, hc.face);
    rt_scene_free(c.s);
}

/* Spans of a CSG node along o + t d: their count, ins and outs and the leaves they enter and leave by. */
typedef struct {
    double tin[8], tout[8];
    int lin[8], lout[8], n;
} spans;

static spans node_spans(const rt_scene *s, int node, const double o[3], const double d[3])
{
    spans sp;
    memset(&sp, 0, sizeof sp);
    sp.n = rt_node_spans(s, node, o, d, 0, INFINITY, sp.tin, sp.tout, sp.lin, sp.lout, 8);
    return sp;
}

static void difference_union_intersection_of_spheres_along_x(ctest *t)
{
    csg_nodes c = csg_scene(t);
    double o[3] = {-5, 0, 0}, d[3] = {1, 0, 0};
    spans p = node_spans(c.s, c.D, o, d);
    CHECKF(t,
           p.n == 1 && fabs(p.tin[0] - 4) < 1e-12 && fabs(p.tout[0] - 5) < 1e-12 && p.lin[0] == c.A && p.lout[0] == c.B,
           "A - B: %d spans [%g, %g] leaves %d %d", p.n, p.tin[0], p.tout[0], p.lin[0], p.lout[0]);
    p = node_spans(c.s, c.U, o, d);
    CHECKF(t,
           p.n == 1 && fabs(p.tin[0] - 4) < 1e-12 && fabs(p.tout[0] - 7) < 1e-12 && p.lin[0] == c.A && p.lout[0] == c.B,
           "A | B: %d spans", p.n);
    p = node_spans(c.s, c.I, o, d);
    CHECKF(t,
           p.n == 1 && fabs(p.tin[0] - 5) < 1e-12 && fabs(p.tout[0] - 6) < 1e-12 && p.lin[0] == c.B && p.lout[0] == c.A,
           "A & B: %d spans", p.n);
    printf("csg spheres along x: A-B, A|B, A&B spans as expected\n");
    rt_scene_free(c.s);
}

/* starting inside A - B: the interval is open at the start, and the ray leaves through B's (flipped) surface */
static void difference_starting_inside(ctest *t)
{
    csg_nodes c = csg_scene(t);
    double o[3] = {-0.5, 0, 0}, d[3] = {1, 0, 0};
    spans p = node_spans(c.s, c.D, o, d);
    rt_hit h;
    CHECKF(t, p.n == 1 && p.tin[0] == 0.0 && p.lin[0] == -1 && fabs(p.tout[0] - 0.5) < 1e-12, "open start");
    CHECKF(t,
           rt_scene_intersect(c.s, o, d, 0, INFINITY, &h) && fabs(h.t - 0.5) < 1e-12 && !h.entering &&
               h.n[0] > 0.999999,
           "leaving A - B through B's (flipped) surface: t %g n (%g %g %g)", h.t, h.n[0], h.n[1], h.n[2]);
    rt_scene_free(c.s);
}

/* from +x: enter A - B through B's surface at x = 0; B's outward normal there is -x, flipped +x */
static void difference_entered_through_the_flipped_surface(ctest *t)
{
    csg_nodes c = csg_scene(t);
    double o[3] = {5, 0, 0}, d[3] = {-1, 0, 0};
    rt_hit h;
    CHECKF(t, rt_scene_intersect(c.s, o, d, 0, INFINITY, &h) == 1, "A - B from +x misses");
    CHECKF(t, fabs(h.t - 5.0) < 1e-12 && h.leaf == c.B && h.entering && fabs(h.n[0] - 1.0) < 1e-12,
           "A - B from +x: t %g leaf %d entering %d n (%g %g %g)", h.t, h.leaf, h.entering, h.n[0], h.n[1], h.n[2]);
    rt_scene_free(c.s);
}

/* tangent: y = 1 grazes both spheres (double roots), so there is no inside anywhere */
static void tangent_ray_has_no_inside(ctest *t)
{
    csg_nodes c = csg_scene(t);
    double o[3] = {-5, 1, 0}, d[3] = {1, 0, 0};
    spans p = node_spans(c.s, c.U, o, d);
    CHECKF(t, p.n == 0, "tangent ray gives %d spans", p.n);
    o[1] = 1.0 - 1e-6; /* just inside: two thin spans which the union merges into one */
    p = node_spans(c.s, c.U, o, d);
    CHECKF(t, p.n == 2, "near-tangent ray gives %d spans, want 2", p.n);
    rt_scene_free(c.s);
}

/* a non-convex leaf: torus (R = 1, r = 0.25) minus the unit sphere, along x */
static void torus_minus_sphere_along_x(ctest *t)
{
    csg_nodes c = csg_scene(t);
    double o[3] = {-5, 0, 0}, d[3] = {1, 0, 0};
    spans p = node_spans(c.s, c.TD, o, d);
    CHECKF(t,
           p.n == 2 && fabs(p.tin[0] - 3.75) < 1e-12 && fabs(p.tout[0] - 4.0) < 1e-12 && fabs(p.tin[1] - 6.0) < 1e-12 &&
               fabs(p.tout[1] - 6.25) < 1e-12 && p.lout[0] == c.S && p.lin[1] == c.S,
           "torus - sphere: %d spans", p.n);
    printf("csg torus - sphere: [%g, %g] [%g, %g]\n", p.tin[0], p.tout[0], p.tin[1], p.tout[1]);
    rt_scene_free(c.s);
}

/* ---------------------------------------------------------------- transforms */

/* M = T R S for the transformed torus; the test composes the inverse independently as S^-1 R^T (p - T). */
static const double TORUS_AXIS[3] = {1, 2, -0.5}, TORUS_S[3] = {2.0, 0.7, 1.3}, TORUS_T[3] = {3, -1, 4};
static const double TORUS_P[2] = {1.0, 0.3};

/* What the transformed torus' rays found: hit/miss disagreements with the inverse-transformed ray, hits, the worst
 * relative t difference, the worst normal . tangent. */
typedef struct {
    int disagree, hits;
    double worst, worst_n;
} torus_tally;

/* The world normal n at the object point p must be perpendicular to M x (two object tangents): the larger
 * |cos| of the two angles. */
static double normal_off_tangents(const double M[12], const double p[3], const double n[3])
{
    double g[3], t1[3], t2[3], w1[3], w2[3], e[3] = {0.3, -0.5, 0.8};
    torus_z_gradient(p, TORUS_P, g);
    /* two tangents: g x e, g x (g x e) */
    t1[0] = g[1] * e[2] - g[2] * e[1];
    t1[1] = g[2] * e[0] - g[0] * e[2];
    t1[2] = g[0] * e[1] - g[1] * e[0];
    t2[0] = g[1] * t1[2] - g[2] * t1[1];
    t2[1] = g[2] * t1[0] - g[0] * t1[2];
    t2[2] = g[0] * t1[1] - g[1] * t1[0];
    rt_xform_vector(M, t1, w1);
    rt_xform_vector(M, t2, w2);
    return fmax(fabs(rt_dot(w1, n)) / sqrt(rt_dot(w1, w1)), fabs(rt_dot(w2, n)) / sqrt(rt_dot(w2, w2)));
}

/* One random ray at the torus: the tracer's hit against the object-space roots of the torus polynomial along the
 * inverse-transformed ray. */
static void torus_ray(const rt_scene *s, const double R[9], const double M[12], unsigned long long *seed,
                      torus_tally *c)
{
    double o[3], d[3], oo[3], od[3], po[3], p[3], cf[5], roots[IG_MAX_DEGREE], first = INFINITY;
    int k, nr, got;
    rt_hit h;
    for (k = 0; k < 3; ++k) {
        o[k] = TORUS_T[k] + 8.0 * urand(seed) - 4.0;
        d[k] = TORUS_T[k] + 1.2 * (2.0 * urand(seed) - 1.0) - o[k];
    }
    for (k = 0; k < 3; ++k)
        po[k] = o[k] - TORUS_T[k];
    for (k = 0; k < 3; ++k) {
        oo[k] = (R[k] * po[0] + R[3 + k] * po[1] + R[6 + k] * po[2]) / TORUS_S[k];
        od[k] = (R[k] * d[0] + R[3 + k] * d[1] + R[6 + k] * d[2]) / TORUS_S[k];
    }
    /* object-space roots of the torus polynomial, straight from the coefficients */
    torus_z_coeffs(oo, od, TORUS_P, cf);
    nr = ig_real_roots(cf, 4, 0.0, 1e3, IG_ROOTS_STURM, roots);
    for (k = 0; k < nr; ++k)
        if (roots[k] > 0.0) {
            first = roots[k];
            break;
        }
    got = rt_scene_intersect(s, o, d, 0, INFINITY, &h);
    if (got != isfinite(first)) {
        ++c->disagree;
        return;
    }
    if (!got)
        return;
    ++c->hits;
    if (fabs(h.t - first) / fmax(1.0, first) > c->worst)
        c->worst = fabs(h.t - first) / fmax(1.0, first);
    for (k = 0; k < 3; ++k)
        p[k] = oo[k] + h.t * od[k];
    c->worst_n = fmax(c->worst_n, normal_off_tangents(M, p, h.n));
}

static void transformed_torus_against_the_inverse_transformed_ray(ctest *t)
{
    double R[9], M[12];
    int i, j;
    unsigned long long seed = 11;
    torus_tally c = {0, 0, 0.0, 0.0};
    rt_scene *s = rt_scene_new();
    rot_axis(TORUS_AXIS, 0.8, R);
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j)
            M[4 * i + j] = R[3 * i + j] * TORUS_S[j];
        M[4 * i + 3] = TORUS_T[i];
    }
    rt_scene_add_object(s, rt_scene_add_leaf(s, &torus_z_shape, TORUS_P, 2, M, add_matte(s)));
    CHECKF(t, rt_scene_commit(s) == 0, "commit");
    for (i = 0; i < 20000; ++i)
        torus_ray(s, R, M, &seed, &c);
    CHECKF(t, c.disagree == 0, "%d rays disagree with the inverse-transformed ray", c.disagree);
    CHECKF(t, c.worst < 1e-9, "worst relative t difference %.3g", c.worst);
    CHECKF(t, c.worst_n < 1e-9, "normal not perpendicular to transformed tangents: %.3g", c.worst_n);
    printf("transformed torus: 20000 rays (%d hits), hit/miss disagreements %d, worst relative t diff %.3g, "
           "normal.tangent %.3g\n",
           c.hits, c.disagree, c.worst, c.worst_n);
    rt_scene_free(s);
}

/* ---------------------------------------------------------------- the piriform in the paper's basis form */

/* position P and axis vectors u, v, w, the columns of the object -> world map */
static const double PIR_P[3] = {2, -1, 5}, PIR_U[3] = {0, 0, 3}, PIR_V[3] = {0, 2, 0}, PIR_W[3] = {-1.5, 0, 0};

static rt_scene *piriform_scene(ctest *t)
{
    double M[12];
    int k;
    rt_scene *s = rt_scene_new();
    for (k = 0; k < 3; ++k) {
        M[4 * k] = PIR_U[k];
        M[4 * k + 1] = PIR_V[k];
        M[4 * k + 2] = PIR_W[k];
        M[4 * k + 3] = PIR_P[k];
    }
    rt_scene_add_object(s, rt_scene_add_leaf(s, &piriform_shape, NULL, 0, M, add_matte(s)));
    CHECKF(t, rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
    return s;
}

/* along the u axis from P - 3u: object ray (-3, 0, 0) + t (1, 0, 0); f = x^3 (x - 1): the cusp at t = 3 (a
 * triple root), the tip at t = 4 */
static void piriform_cusp_and_tip(ctest *t)
{
    rt_scene *s = piriform_scene(t);
    double o[3], d[3];
    int k;
    rt_hit h;
    for (k = 0; k < 3; ++k) {
        o[k] = PIR_P[k] - 3 * PIR_U[k];
        d[k] = PIR_U[k];
    }
    CHECKF(t, rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1, "piriform axis ray misses");
    CHECKF(t, fabs(h.t - 3.0) < 1e-4, "cusp at t = %.17g, want 3", h.t);
    CHECKF(t, isfinite(h.n[0]) && isfinite(h.n[1]) && isfinite(h.n[2]) && fabs(rt_dot(h.n, h.n) - 1) < 1e-12,
           "cusp normal not finite/unit");
    printf("piriform cusp: t = %.12g (want 3), singular %d, normal (%g %g %g)\n", h.t, h.singular, h.n[0], h.n[1],
           h.n[2]);
    CHECKF(t, rt_scene_intersect(s, o, d, 3.5, INFINITY, &h) == 1 && fabs(h.t - 4.0) < 1e-12,
           "tip at t = %.17g, want 4", h.t);
    rt_scene_free(s);
}

/* through object point (0.5, y, 0) along v: y^2 = 0.0625 gives t = 1.75 and 2.25; the object gradient
 * (-0.25, -0.5, 0) maps to g_x u/|u|^2 + g_y v/|v|^2 + g_z w/|w|^2 */
static void piriform_normal_through_the_basis(ctest *t)
{
    rt_scene *s = piriform_scene(t);
    double o[3], d[3], g[3] = {-0.25, -0.5, 0}, want[3], l;
    int k;
    rt_hit h;
    for (k = 0; k < 3; ++k) {
        o[k] = PIR_P[k] + 0.5 * PIR_U[k] - 2 * PIR_V[k];
        d[k] = PIR_V[k];
    }
    CHECKF(t, rt_scene_intersect(s, o, d, 0, INFINITY, &h) == 1 && fabs(h.t - 1.75) < 1e-12, "t = %.17g want 1.75",
           h.t);
    for (k = 0; k < 3; ++k)
        want[k] = g[0] * PIR_U[k] / 9.0 + g[1] * PIR_V[k] / 4.0 + g[2] * PIR_W[k] / 2.25;
    l = sqrt(rt_dot(want, want));
    for (k = 0; k < 3; ++k)
        CHECKF(t, fabs(h.n[k] - want[k] / l) < 1e-12, "piriform normal[%d]", k);
    CHECKF(t, rt_scene_intersect(s, o, d, 1.8, INFINITY, &h) == 1 && fabs(h.t - 2.25) < 1e-12, "second root");
    rt_scene_free(s);
}

/* every case of the driver, those of tracer_rays_optics.c too, in the order the sections run */
static const ctest_case CASES[] = {
    CTEST_CASE(sphere_along_its_axis),
    CTEST_CASE(scaled_sphere),
    CTEST_CASE(sphere_random_rays_against_the_closest_root),
    CTEST_CASE(snell_on_random_rays),
    CTEST_CASE(total_internal_reflection_beyond_the_critical_angle),
    CTEST_CASE(fresnel_at_normal_incidence_brewster_and_grazing),
    CTEST_CASE(mirror_reflection),
    CTEST_CASE(capped_cylinder_closed_by_its_box_faces),
    CTEST_CASE(difference_union_intersection_of_spheres_along_x),
    CTEST_CASE(difference_starting_inside),
    CTEST_CASE(difference_entered_through_the_flipped_surface),
    CTEST_CASE(tangent_ray_has_no_inside),
    CTEST_CASE(torus_minus_sphere_along_x),
    CTEST_CASE(transformed_torus_against_the_inverse_transformed_ray),
    CTEST_CASE(piriform_cusp_and_tip),
    CTEST_CASE(piriform_normal_through_the_basis),
    CTEST_CASE(point_light_shading_and_shadow),
    CTEST_CASE(glass_ball_beer_lambert),
    CTEST_CASE(total_internal_reflection_traps_a_ray_in_a_ball),
    CTEST_CASE(index_matched_absorbing_csg_shell),
    CTEST_CASE(shadow_through_glass),
    CTEST_CASE(shortcuts_on_20000_random_rays),
    CTEST_CASE(checker_colour_beyond_2_53),
    CTEST_CASE(plane_path_against_long_double_and_the_general_solve),
    CTEST_CASE(plane_path_parallel_inside_and_beyond_far),
};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
