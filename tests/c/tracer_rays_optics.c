/* Ray-level tests of the tracer's optics and shading against analytic answers, as named cases: Snell, total
 * internal reflection, Fresnel, reflection; point-light shading and shadows; glass (Beer-Lambert, CSG
 * boundaries, coloured shadows); the tracer's own shortcuts and the plane path. Part of the tracer_rays test
 * (tracer_rays.c holds main and the table of cases; tracer_rays.h declares these). */
#include "tracer_rays.h"
#include "plane_y.h"

/* ---------------------------------------------------------------- optics */
static const double UP_NORMAL[3] = {0, 1, 0};

void snell_on_random_rays(ctest *t)
{
    const double *n = UP_NORMAL;
    double worst_snell = 0.0, worst_plane = 0.0;
    int i, tir_wrong = 0;
    unsigned long long seed = 7;
    double etas[4] = {1.0 / 1.5, 1.5, 1.0 / 1.33, 2.4};
    for (i = 0; i < 40000; ++i) {
        double eta = etas[i % 4], th = 0.5 * M_PI * urand(&seed), ph = 2 * M_PI * urand(&seed);
        double d[3] = {sin(th) * cos(ph), -cos(th), sin(th) * sin(ph)}, tr[3], crit;
        int ok = rt_refract(d, n, eta, tr);
        crit = eta > 1.0 ? asin(1.0 / eta) : M_PI;
        if ((th > crit + 1e-12 && ok) || (th < crit - 1e-12 && !ok))
            ++tir_wrong;
        if (ok) {
            double st = sqrt(tr[0] * tr[0] + tr[2] * tr[2]);
            double e = fabs(eta * sin(th) - st);
            /* coplanar: the refracted ray lies in the plane of d and n */
            double cx[3] = {d[1] * n[2] - d[2] * n[1], d[2] * n[0] - d[0] * n[2], d[0] * n[1] - d[1] * n[0]};
            double pe = fabs(rt_dot(cx, tr));
            if (e > worst_snell)
                worst_snell = e;
            if (pe > worst_plane)
                worst_plane = pe;
            CHECKF(t, tr[1] < 0.0 || th > 1.5707, "refracted ray must go through the surface");
        }
    }
    CHECKF(t, worst_snell < 1e-14, "Snell residual %.3g", worst_snell);
    CHECKF(t, worst_plane < 1e-14, "coplanarity residual %.3g", worst_plane);
    CHECKF(t, tir_wrong == 0, "%d rays on the wrong side of the critical angle", tir_wrong);
    printf("snell: 40000 rays, worst |eta sin(i) - sin(t)| %.3g, coplanarity %.3g, TIR misclassified %d\n", worst_snell,
           worst_plane, tir_wrong);
}

/* 0.9 rad > asin(1/1.5) = 0.7297: total internal reflection going from glass to air; 0.72 rad is below it */
void total_internal_reflection_beyond_the_critical_angle(ctest *t)
{
    double d[3] = {sin(0.9), -cos(0.9), 0}, tr[3];
    CHECKF(t, rt_refract(d, UP_NORMAL, 1.5, tr) == 0, "TIR expected at 0.9 rad");
    CHECKF(t, rt_fresnel(cos(0.9), 1.5) == 1.0, "Fresnel must be 1 under TIR");
    d[0] = sin(0.72);
    d[1] = -cos(0.72);
    CHECKF(t, rt_refract(d, UP_NORMAL, 1.5, tr) == 1, "no TIR expected at 0.72 rad");
}

void fresnel_at_normal_incidence_brewster_and_grazing(ctest *t)
{
    double r0 = rt_fresnel(1.0, 1.0 / 1.5), want = 0.04, brew = atan(1.5), rb, rs;
    double ct = cos(asin(sin(brew) / 1.5));
    CHECKF(t, fabs(r0 - want) < 1e-15, "normal incidence R = %.17g", r0);
    /* at Brewster's angle only the s-polarised part reflects: R = rs^2 / 2 */
    rs = (cos(brew) - 1.5 * ct) / (cos(brew) + 1.5 * ct);
    rb = rt_fresnel(cos(brew), 1.0 / 1.5);
    CHECKF(t, fabs(rb - 0.5 * rs * rs) < 1e-15, "Brewster R = %.17g want %.17g", rb, 0.5 * rs * rs);
    CHECKF(t, rt_fresnel(1e-9, 1.0 / 1.5) > 0.999, "grazing incidence must reflect almost all");
    printf("fresnel: R(0) = %.17g, R(Brewster) = %.17g (want %.17g)\n", r0, rb, 0.5 * rs * rs);
}

void mirror_reflection(ctest *t)
{
    double d[3] = {1, -1, 0}, r[3];
    rt_reflect(d, UP_NORMAL, r);
    CHECKF(t, fabs(r[0] - M_SQRT1_2) < 1e-15 && fabs(r[1] - M_SQRT1_2) < 1e-15, "mirror reflection");
}

/* ---------------------------------------------------------------- point-light shading and a shadow */

/* Shading against hand-computed values: a point light, an occluder, the background. (Unbounded planes are
 * exercised by the Python render tests, which generate a plane shape.) */
void point_light_shading_and_shadow(ctest *t)
{
    rt_scene *s = rt_scene_new();
    double one = 1.0, m[12], eye[3] = {0, 0, 10}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0}, bg[3] = {0.1, 0.2, 0.3};
    double lp[3] = {0, 0, 10}, lc[3] = {1, 1, 1}, rgb[3], st[RT_NSTATS] = {0, 0, 0};
    double o[3] = {0, 5, 10}, d[3] = {0, 0, -1}, L[3] = {-0.6, 0, 9.2}, nl;
    int mat = add_matte(s);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, IDENTITY, mat));
    translate_scale(m, 0, 0, 3, 0.2); /* small occluder between the light and the sphere's front */
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, m, mat));
    rt_scene_add_light(s, lp, lc);
    rt_scene_set_camera(s, eye, at, up, 30);
    rt_scene_set_background(s, bg);
    CHECKF(t, rt_scene_commit(s) == 0, "commit");
    rt_trace_ray(s, o, d, 4, rgb, st);
    CHECKF(t, rgb[0] == 0.1 && rgb[1] == 0.2 && rgb[2] == 0.3, "a miss shows the background");
    /* lit point: (0.6, 0, 0.8) seen from the light direction; diffuse 0.9 * 0.8 * n.l + ambient 0.08 */
    o[0] = 0.6;
    o[1] = 0;
    nl = (0.6 * L[0] + 0.8 * L[2]) / sqrt(rt_dot(L, L));
    rt_trace_ray(s, o, d, 4, rgb, st);
    CHECKF(t, fabs(rgb[0] - (0.08 + 0.72 * nl)) < 1e-9, "lit colour %.17g want %.17g", rgb[0], 0.08 + 0.72 * nl);
    /* the point (0, 0, 1) is shadowed by the occluder at z = 3: ambient only; the camera ray hits the occluder
     * first, then a ray from just in front of the sphere */
    o[0] = 0;
    rt_trace_ray(s, o, d, 4, rgb, st);
    o[2] = 2.0;
    rt_trace_ray(s, o, d, 4, rgb, st);
    CHECKF(t, fabs(rgb[0] - 0.08) < 1e-12, "shadowed colour %.17g want ambient 0.08", rgb[0]);
    CHECKF(t, st[RT_RAYS_PRIMARY] == 4 && st[RT_RAYS_SHADOW] >= 2, "ray counts %g %g", st[0], st[1]);
    rt_scene_free(s);
}

/* ---------------------------------------------------------------- glass: Beer-Lambert, CSG boundaries, shadows */
static const double SIGMA[3] = {0.5, 1.0, 2.0}, GLASS_BG[3] = {1.0, 0.8, 0.6};

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

/* The unit ball of glass (index ior, transparency 1, absorption sigma) before the glass background. */
static rt_scene *glass_ball(ctest *t, double ior, const double sigma[3], int camera)
{
    double one = 1.0, m[RT_MATERIAL_DOUBLES], eye[3] = {0, 0, 10}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    rt_scene *s = rt_scene_new();
    int g;
    glass_material(m, ior, 1.0, sigma[0], sigma[1], sigma[2]);
    g = rt_scene_add_material(s, m);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, IDENTITY, g));
    if (camera)
        rt_scene_set_camera(s, eye, at, up, 30);
    rt_scene_set_background(s, GLASS_BG);
    CHECKF(t, rt_scene_commit(s) == 0, "commit");
    return s;
}

/* A solid glass ball (n = 1.5) along its diameter, recursion depth 2: the front face reflects F of the
 * background; the rest crosses 2 units of glass, and F of it reflects inside (and ends at the depth limit,
 * black) while 1 - F leaves: F bg + (1 - F)^2 exp(-2 sigma) bg, F = ((1.5 - 1)/(1.5 + 1))^2. */
void glass_ball_beer_lambert(ctest *t)
{
    rt_scene *s = glass_ball(t, 1.5, SIGMA, 1);
    const double *bg = GLASS_BG;
    double F = 0.04, o[3] = {0, 0, 5}, d[3] = {0, 0, -1}, rgb[3];
    int a;
    rt_trace_ray(s, o, d, 2, rgb, NULL);
    for (a = 0; a < 3; ++a) {
        double want = F * bg[a] + (1 - F) * (1 - F) * exp(-2 * SIGMA[a]) * bg[a];
        CHECKF(t, fabs(rgb[a] - want) < 1e-12, "Beer-Lambert channel %d: %.17g want %.17g", a, rgb[a], want);
    }
    printf("glass ball, depth 2: (%.6f %.6f %.6f) = F bg + (1-F)^2 exp(-2 sigma) bg\n", rgb[0], rgb[1], rgb[2]);
    rt_scene_free(s);
}

/* From inside the ball (no absorption): a chord meeting the surface at 60 degrees is beyond the critical angle
 * asin(1/1.5) = 41.8 degrees, so every bounce is a total internal reflection, the ray never leaves and the depth
 * limit ends it in black. At 30 degrees the surface lets (1 - F(30 deg)) of the background through, plus what
 * the reflections bring. A chord from a point at distance sin(a) from the centre, heading along x, meets the
 * sphere with incidence angle a. */
void total_internal_reflection_traps_a_ray_in_a_ball(ctest *t)
{
    const double clear[3] = {0, 0, 0}, *bg = GLASS_BG;
    rt_scene *s2 = glass_ball(t, 1.5, clear, 0);
    double o[3] = {0, 0, 0}, d60[3] = {1, 0, 0}, d30[3] = {1, 0, 0}, Ft, c60[3], c30[3];
    int a;
    o[1] = -sin(60.0 * M_PI / 180.0);
    rt_trace_ray(s2, o, d60, 12, c60, NULL);
    o[1] = -sin(30.0 * M_PI / 180.0);
    rt_trace_ray(s2, o, d30, 12, c30, NULL);
    Ft = rt_fresnel(cos(30.0 * M_PI / 180.0), 1.5);
    CHECKF(t, c60[0] == 0.0 && c60[1] == 0.0 && c60[2] == 0.0, "TIR must trap the ray: (%g %g %g)", c60[0], c60[1],
           c60[2]);
    for (a = 0; a < 3; ++a)
        CHECKF(t, c30[a] >= (1 - Ft) * bg[a] - 1e-12 && c30[a] <= bg[a] + 1e-12, "30 deg: %g (F %g)", c30[a], Ft);
    printf("inside the ball: 60 deg -> (%g %g %g) (trapped), 30 deg -> %.6f >= (1 - F) bg = %.6f\n", c60[0], c60[1],
           c60[2], c30[0], (1 - Ft) * bg[0]);
    rt_scene_free(s2);
}

/* An index-matched (n = 1, so F = 0 and rays go straight) absorbing shell: sphere r = 1 minus sphere r = 0.5.
 * Every ray must cross all four CSG boundaries and absorb over exactly the glass path: 2 sqrt(1 - h^2) -
 * 2 sqrt(0.25 - h^2) at height h < 0.5, 2 sqrt(1 - h^2) above. */
void index_matched_absorbing_csg_shell(ctest *t)
{
    rt_scene *s = rt_scene_new();
    double one = 1.0, half = 0.5, m[RT_MATERIAL_DOUBLES], half_m[12], rgb[3], worst = 0.0;
    int k, a, g, A, B;
    glass_material(m, 1.0, 1.0, SIGMA[0], SIGMA[1], SIGMA[2]);
    g = rt_scene_add_material(s, m);
    A = rt_scene_add_leaf(s, &sphere_shape, &one, 1, IDENTITY, g);
    translate_scale(half_m, 0, 0, 0, 1.0);
    B = rt_scene_add_leaf(s, &sphere_shape, &half, 1, half_m, g);
    rt_scene_add_object(s, rt_scene_add_csg(s, RT_DIFFERENCE, A, B, g));
    rt_scene_set_background(s, GLASS_BG);
    CHECKF(t, rt_scene_commit(s) == 0, "commit");
    for (k = 0; k < 200; ++k) {
        double h = 0.995 * k / 200.0, o[3] = {h, 0, 5}, d[3] = {0, 0, -1}, L;
        L = 2 * sqrt(1 - h * h) - (h < 0.5 ? 2 * sqrt(0.25 - h * h) : 0.0);
        rt_trace_ray(s, o, d, 8, rgb, NULL);
        for (a = 0; a < 3; ++a) {
            double e = fabs(rgb[a] - exp(-SIGMA[a] * L) * GLASS_BG[a]);
            if (e > worst)
                worst = e;
        }
    }
    /* each boundary moves the path by its error bound (~1e-12 here) */
    CHECKF(t, worst < 1e-10, "absorbing CSG shell: worst error %.3g", worst);
    printf("index-matched CSG shell: 200 rays, worst |rgb - exp(-sigma L) bg| %.3g\n", worst);
    rt_scene_free(s);
}

/* A clear ball (transparency 0.8, absorption sigma) between a light and a matte sphere's top point; the light
 * reaching it is 0.8 exp(-sigma * 2) (the shadow ray crosses the diameter), so the colour is ambient +
 * 0.8 exp(-2 sigma) * diffuse * n.l (n.l = 1). */
void shadow_through_glass(ctest *t)
{
    rt_scene *s = rt_scene_new();
    double mm[RT_MATERIAL_DOUBLES] = {1, 1, 1, 0, 0, 0, 0, 0.1, 0.9, 0, 10, 0, 0, 1.5, 0, 0, 0, 0, 0};
    double one = 1.0, big = 10.0, lp[3] = {0, 20, 0}, lc[3] = {1, 1, 1}, mg[12], m[RT_MATERIAL_DOUBLES], rgb[3];
    double o[3] = {0, 1e-3, 3}, d[3] = {0, -1e-3, -3}; /* reaches (0, 0, 0) from the side */
    int a, g, matte = rt_scene_add_material(s, mm);
    glass_material(m, 1.5, 0.8, SIGMA[0], SIGMA[1], SIGMA[2]);
    g = rt_scene_add_material(s, m);
    translate_scale(mg, 0, -10, 0, 1.0);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &big, 1, mg, matte)); /* top point (0, 0, 0) */
    translate_scale(mg, 0, 5, 0, 1.0);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &one, 1, mg, g));
    rt_scene_add_light(s, lp, lc);
    CHECKF(t, rt_scene_commit(s) == 0, "commit");
    rt_trace_ray(s, o, d, 4, rgb, NULL);
    for (a = 0; a < 3; ++a) {
        double want = 0.1 + 0.8 * exp(-2 * SIGMA[a]) * 0.9;
        CHECKF(t, fabs(rgb[a] - want) < 1e-9, "shadow through glass channel %d: %.17g want %.17g", a, rgb[a], want);
    }
    rt_scene_free(s);
}

/* ---------------------------------------------------------------- the tracer's own shortcuts */

/* The plane y = 0 (plane_y.h) as a hand-written unbounded shape of degree 1. */
static int plane_bounds(const double *p, double box[6])
{
    (void)p;
    box[0] = box[1] = box[2] = -INFINITY;
    box[3] = box[4] = box[5] = INFINITY;
    return 0;
}
static const ig_shape plane_y = {"plane_y", 1, 0, plane_y_coeffs, plane_y_value, plane_y_gradient, plane_bounds, 0};

/* A tilted plane, a transformed torus, an opaque sphere and a glass sphere: the scene and two of its objects. */
typedef struct {
    rt_scene *s;
    int plane, gball;
} shortcut_scene;

static shortcut_scene shortcuts_scene(ctest *t)
{
    double one = 1.0, tp[2] = {1.0, 0.3}, M[12], R[9], axis[3] = {0.3, 1, 0.2}, pl[12];
    double glass[RT_MATERIAL_DOUBLES] = {1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0.9, 1.5, 0, 0, 0, 0, 0};
    shortcut_scene c;
    int i, k, mat, gmat;
    c.s = rt_scene_new();
    mat = add_matte(c.s);
    gmat = rt_scene_add_material(c.s, glass);
    rot_axis(axis, 0.4, R);
    for (i = 0; i < 3; ++i) {
        for (k = 0; k < 3; ++k) {
            M[4 * i + k] = 1.3 * R[3 * i + k];
            pl[4 * i + k] = R[3 * i + k];
        }
        M[4 * i + 3] = i == 1 ? 1.5 : 0.2;
        pl[4 * i + 3] = i == 1 ? -0.5 : 0.0;
    }
    c.plane = rt_scene_add_object(c.s, rt_scene_add_leaf(c.s, &plane_y, NULL, 0, pl, mat));
    rt_scene_add_object(c.s, rt_scene_add_leaf(c.s, &torus_z_shape, tp, 2, M, mat));
    translate_scale(M, -2.5, 1, 0, 0.8);
    rt_scene_add_object(c.s, rt_scene_add_leaf(c.s, &sphere_shape, &one, 1, M, mat));
    translate_scale(M, 2.5, 1, 0.5, 0.8);
    c.gball = rt_scene_add_object(c.s, rt_scene_add_leaf(c.s, &sphere_shape, &one, 1, M, gmat));
    CHECKF(t, rt_scene_commit(c.s) == 0, "commit: %s", rt_scene_error(c.s));
    return c;
}

/* What the shortcuts' random rays found. */
typedef struct {
    int same, hits, any_ok, any_n, any_behind, self, spawned;
} shortcut_tally;

/* The error bound worked out later (rt_hit_error) is the one rt_scene_intersect gives at once; a ray leaving the
 * plane never meets the plane again (why rays spawned there skip it). */
static void lazy_bound_and_plane_skip(ctest *t, const shortcut_scene *sc, const double o[3], const double d[3],
                                      unsigned long long *seed, shortcut_tally *c)
{
    double q[3], L[3] = {0, 0, 0};
    int i;
    rt_pending ph;
    rt_hit eager, lazy_hit;
    rt_hit_lazy lz;
    if (!rt_scene_intersect(sc->s, o, d, 0, INFINITY, &eager))
        return;
    ++c->hits;
    CHECKF(t, rt_scene_closest(sc->s, o, d, 0, INFINITY, RT_CLOSEST, -1, &ph), "closest disagrees with intersect");
    rt_finish_hit(sc->s, &ph, o, d, &lazy_hit, &lz);
    rt_hit_error(sc->s, &lazy_hit, &lz);
    rt_hit_error(sc->s, &lazy_hit, &lz); /* a second call changes nothing */
    c->same += memcmp(&eager, &lazy_hit, sizeof eager) == 0;
    if (eager.object == sc->plane) {
        for (i = 0; i < 3; ++i)
            L[i] = 2 * urand(seed) - 1;
        rt_spawn_origin(&eager, L, q);
        ++c->spawned;
        if (rt_scene_closest(sc->s, q, L, 0, INFINITY, RT_CLOSEST, -1, &ph) && ph.object == sc->plane)
            ++c->self;
        CHECKF(t, rt_spawn_skip(sc->s, &eager) == sc->plane, "a plane hit must skip the plane");
    } else {
        CHECKF(t, rt_spawn_skip(sc->s, &eager) == -1, "only planes are skipped");
    }
}

/* RT_ANY_OPAQUE: an opaque hit whenever the segment holds one, else the closest (transparent) hit */
static void any_opaque_on_a_segment(ctest *t, const shortcut_scene *sc, const double o[3], const double d[3],
                                    shortcut_tally *c)
{
    rt_pending pc, pa, ph;
    int hc = rt_scene_closest(sc->s, o, d, 0, 12.0, RT_CLOSEST, -1, &pc);
    int ha = rt_scene_closest(sc->s, o, d, 0, 12.0, RT_ANY_OPAQUE, -1, &pa);
    int opaque_in_range = 0;
    double tk = 0.0;
    /* walk the segment's hits in order to see whether any is opaque */
    while (rt_scene_closest(sc->s, o, d, tk, 12.0, RT_CLOSEST, -1, &ph)) {
        if (ph.object != sc->gball) {
            opaque_in_range = 1;
            break;
        }
        tk = ph.t;
    }
    if (hc) {
        ++c->any_n;
        if (opaque_in_range) {
            c->any_ok += ha && pa.object != sc->gball;
            c->any_behind += pc.object == sc->gball; /* the opaque hit lies behind the glass */
        } else {
            c->any_ok += ha && pa.object == sc->gball && pa.t == pc.t;
        }
    } else {
        CHECKF(t, !ha, "RT_ANY_OPAQUE finds a hit where RT_CLOSEST finds none");
    }
}

void shortcuts_on_20000_random_rays(ctest *t)
{
    shortcut_scene sc = shortcuts_scene(t);
    shortcut_tally c = {0, 0, 0, 0, 0, 0, 0};
    unsigned long long seed = 99;
    int i, k;
    for (k = 0; k < 20000; ++k) {
        double o[3], d[3];
        for (i = 0; i < 3; ++i) {
            o[i] = 12 * urand(&seed) - 6;
            d[i] = 2 * urand(&seed) - 1;
        }
        o[1] += 8.0;
        lazy_bound_and_plane_skip(t, &sc, o, d, &seed, &c);
        any_opaque_on_a_segment(t, &sc, o, d, &c);
    }
    CHECKF(t, c.hits > 5000 && c.same == c.hits, "lazy error bound: %d of %d hits identical", c.same, c.hits);
    CHECKF(t, c.self == 0 && c.spawned > 1000, "rays leaving the plane met it again %d times of %d", c.self, c.spawned);
    CHECKF(t, c.any_ok == c.any_n && c.any_n > 1000 && c.any_behind > 10,
           "RT_ANY_OPAQUE right on %d of %d segments (%d behind glass)", c.any_ok, c.any_n, c.any_behind);
    printf("shortcuts: %d hits, lazy error bound identical on %d; %d rays off the plane, %d met it again; any-opaque "
           "right on %d of %d segments, %d of them opaque behind glass\n",
           c.hits, c.same, c.spawned, c.self, c.any_ok, c.any_n, c.any_behind);
    rt_scene_free(sc.s);
}

/* The checker (ambient 1, nothing else: the colour is the cell colour) against the fmod formula, at cell indices
 * of both signs and beyond 2^53, where every double is an even integer. */
void checker_colour_beyond_2_53(ctest *t)
{
    double checker[RT_MATERIAL_DOUBLES] = {1, 1, 1, 0, 0, 0, 0.7, 1, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0};
    /* the generator's state after shortcuts_on_20000_random_rays' draws from seed 99: the points always checked */
    unsigned long long seed = 18171007234106707310ULL;
    rt_scene *c = rt_scene_new();
    int i, k, cm = rt_scene_add_material(c, checker), wrong = 0, n = 0;
    double rgb[3];
    rt_scene_add_object(c, rt_scene_add_leaf(c, &plane_y, NULL, 0, IDENTITY, cm));
    CHECKF(t, rt_scene_commit(c) == 0, "commit: %s", rt_scene_error(c));
    for (k = 0; k < 4000; ++k) {
        double mag = pow(10.0, 17.0 * urand(&seed)), x = (2 * urand(&seed) - 1) * mag, z = (2 * urand(&seed) - 1) * mag,
               o[3], d[3] = {0, -1, 0}, sum = 0.0, want, q[3];
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
    CHECKF(t, wrong == 0, "checker colour wrong at %d of %d points", wrong, n);
    rt_scene_free(c);
}

/* ---------------------------------------------------------------- the plane path */

/* The plane path of rt_object_hit (a top-level leaf of degree 1 without bounds: one division instead of the
 * general solve). Its t against the plane's answer worked out in long double from the transform, and against
 * the general solve of the same leaf (rt_leaf_roots); rays parallel to the plane, starting on it, or with a
 * direction component below the normal range (the general path decides those). */

/* A random rotation R, non-uniform scales 1e-2 .. 1e2 on odd trials, a translation T (up to 1e4 on every third
 * trial): the map M = T R S, and the condition number of S. */
static double plane_map(unsigned long long *seed, int trial, double R[9], double M[12], double T[3])
{
    double axis[3], sc[3];
    int i, k;
    for (i = 0; i < 3; ++i) {
        axis[i] = 2 * urand(seed) - 1;
        sc[i] = trial % 2 ? pow(10.0, 4 * urand(seed) - 2) : 1.0;
        T[i] = trial % 3 ? 20 * urand(seed) - 10 : 1e4 * (2 * urand(seed) - 1);
    }
    rot_axis(axis, 6.28 * urand(seed), R);
    for (i = 0; i < 3; ++i) {
        for (k = 0; k < 3; ++k)
            M[4 * i + k] = R[3 * i + k] * sc[k];
        M[4 * i + 3] = T[i];
    }
    return fmax(fmax(sc[0], sc[1]), sc[2]) / fmin(fmin(sc[0], sc[1]), sc[2]);
}

/* What the plane path's random rays found: hits (in units of the tolerance, the worst), misses, and agreement with
 * the general solve. */
typedef struct {
    int hits, misses, agree;
    double worst, worst_general;
} plane_tally;

/* One random ray at the plane object obj of s (world map from R and T, condition cond). */
static void plane_ray(ctest *t, const rt_scene *s, int obj, const double R[9], const double T[3], double cond,
                      unsigned long long *seed, plane_tally *c)
{
    double o[3], d[3], len = pow(10.0, 6 * urand(seed) - 3), oo[3], od[3], r[IG_MAX_DEGREE + 2];
    long double num = 0, den = 0, ts, mag = 0, magd = 0;
    rt_pending ph;
    int i, got, ng;
    for (i = 0; i < 3; ++i) {
        o[i] = T[i] + 40 * urand(seed) - 20;
        d[i] = len * (2 * urand(seed) - 1);
    }
    /* world plane: column 1 of R (the object y axis, scaled) dotted with p - T vanishes */
    for (i = 0; i < 3; ++i) {
        num += (long double)R[3 * i + 1] * ((long double)T[i] - o[i]);
        den += (long double)R[3 * i + 1] * d[i];
        mag += fabsl((long double)R[3 * i + 1]) * (fabsl((long double)o[i]) + fabsl((long double)T[i]));
        magd += fabsl((long double)R[3 * i + 1] * d[i]);
    }
    ts = num / den;
    got = rt_scene_closest(s, o, d, 0, INFINITY, RT_CLOSEST, -1, &ph);
    rt_to_object(&s->nodes[s->objects[obj]], o, d, oo, od);
    ng = rt_leaf_roots(&s->nodes[s->objects[obj]], oo, od, 0, INFINITY, r);
    if (ts > 0 && ts * len < 0.5 * s->far) {
        /* t is off by the rounding of f(o) (relative to |o| + |T|) and of c1 (relative to the sum of |terms|: a
         * grazing ray cancels), times the condition number of the transform (its inverse is rounded) */
        long double tol = 64 * DBL_EPSILON * cond * (mag + ts * magd) / fabsl(den);
        long double e = fabsl(ph.t - ts) / tol;
        CHECKF(t, got && ph.object == obj, "plane path: no hit at t = %.17g", (double)ts);
        if (got) {
            ++c->hits;
            c->worst = (double)e > c->worst ? (double)e : c->worst;
        }
        if (ng > 0) {
            double eg = (double)(fabsl(r[0] - ts) / tol);
            c->worst_general = eg > c->worst_general ? eg : c->worst_general;
            c->agree += got && fabs(r[0] - ph.t) <= (double)tol;
        }
    } else if (ts <= 0) {
        CHECKF(t, !got, "plane path: a hit at t = %.17g behind the ray (plane at %.17g)", ph.t, (double)ts);
        ++c->misses;
    }
}

/* 40 random rotated, scaled and translated planes, 500 rays each */
void plane_path_against_long_double_and_the_general_solve(ctest *t)
{
    unsigned long long seed = 4242;
    plane_tally c = {0, 0, 0, 0.0, 0.0};
    int trial, k;
    for (trial = 0; trial < 40; ++trial) {
        double R[9], M[12], T[3], cond;
        rt_scene *s = rt_scene_new();
        int obj, mat = add_matte(s);
        cond = plane_map(&seed, trial, R, M, T);
        obj = rt_scene_add_object(s, rt_scene_add_leaf(s, &plane_y, NULL, 0, M, mat));
        CHECKF(t, rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
        for (k = 0; k < 500; ++k)
            plane_ray(t, s, obj, R, T, cond, &seed, &c);
        rt_scene_free(s);
    }
    CHECKF(t, c.worst <= 1.0 && c.hits > 5000 && c.misses > 5000,
           "plane path: worst %.3g of tolerance, %d hits, %d misses", c.worst, c.hits, c.misses);
    CHECKF(t, c.agree == c.hits, "plane path and general solve agree on %d of %d hits", c.agree, c.hits);
    printf("plane path: %d hits within %.3g of the tolerance (general solve %.3g), %d misses\n", c.hits, c.worst,
           c.worst_general, c.misses);
}

/* parallel, on the plane, a tiny direction component: the general path's answer */
void plane_path_parallel_inside_and_beyond_far(ctest *t)
{
    rt_scene *s = rt_scene_new();
    double o[3] = {0.3, 2.0, -1.0}, d[3] = {1.0, 0.0, 0.5}, on[3] = {0.3, 0.0, -1.0}, up[3] = {0.1, 1.0, 0};
    double tiny[3] = {1.0, -1e-310, 0.0};
    rt_pending ph;
    int mat = add_matte(s);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &plane_y, NULL, 0, IDENTITY, mat));
    CHECKF(t, rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
    CHECKF(t, !rt_scene_closest(s, o, d, 0, INFINITY, RT_CLOSEST, -1, &ph), "a ray parallel to the plane hits it");
    CHECKF(t, !rt_scene_closest(s, on, up, 0, INFINITY, RT_CLOSEST, -1, &ph), "a ray leaving the plane hits it");
    CHECKF(t, !rt_scene_closest(s, on, d, 0, INFINITY, RT_CLOSEST, -1, &ph), "a ray inside the plane hits it");
    d[1] = -1.0;
    CHECKF(t, rt_scene_closest(s, o, d, 0, INFINITY, RT_CLOSEST, -1, &ph) && ph.t == 2.0, "t = %.17g, not 2", ph.t);
    /* c1 = -1e-310 is subnormal: the general path's root at 2e310 lies beyond the scene's far limit */
    CHECKF(t, !rt_scene_closest(s, o, tiny, 0, INFINITY, RT_CLOSEST, -1, &ph), "a hit beyond the far limit");
    rt_scene_free(s);
}
