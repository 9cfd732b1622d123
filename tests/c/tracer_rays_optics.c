/* Ray-level tests of the tracer's optics and shading against analytic answers: Snell, total internal
 * reflection, Fresnel, reflection; point-light shading and shadows on an unbounded plane; glass (Beer-Lambert,
 * CSG boundaries, coloured shadows); the tracer's own shortcuts. Part of the tracer_rays test (tracer_rays.c
 * holds main). */
#include "tracer_rays.h"
#include "plane_y.h"

/* ---------------------------------------------------------------- optics */
void test_optics(void)
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
/* ---------------------------------------------------------------- an unbounded plane and a shadow */
void test_unbounded_and_shading(void)
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

void test_glass(void)
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

/* The plane y = 0 (plane_y.h) as a hand-written unbounded shape of degree 1. */
static int plane_bounds(const double *p, double box[6])
{
    (void)p;
    box[0] = box[1] = box[2] = -INFINITY;
    box[3] = box[4] = box[5] = INFINITY;
    return 0;
}
static const ig_shape plane_y = {"plane_y", 1, 0, plane_y_coeffs, plane_y_value, plane_y_gradient, plane_bounds};

void test_shortcuts(void)
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

/* The plane path of rt_object_hit (a top-level leaf of degree 1 without bounds: one division instead of the
 * general solve). Its t against the plane's answer worked out in long double from the transform, and against
 * the general solve of the same leaf (rt_leaf_roots); rays parallel to the plane, starting on it, or with a
 * direction component below the normal range (the general path decides those). */
void test_plane_path(void)
{
    unsigned long long seed = 4242;
    double worst = 0.0, worst_general = 0.0;
    int trial, hits = 0, misses = 0, agree = 0;
    for (trial = 0; trial < 40; ++trial) {
        double R[9], M[12], axis[3], sc[3], T[3], cond;
        rt_scene *s = rt_scene_new();
        int i, k, obj, mat = add_matte(s);
        for (i = 0; i < 3; ++i) {
            axis[i] = 2 * urand(&seed) - 1;
            sc[i] = trial % 2 ? pow(10.0, 4 * urand(&seed) - 2) : 1.0; /* non-uniform scales 1e-2 .. 1e2 */
            T[i] = trial % 3 ? 20 * urand(&seed) - 10 : 1e4 * (2 * urand(&seed) - 1);
        }
        cond = fmax(fmax(sc[0], sc[1]), sc[2]) / fmin(fmin(sc[0], sc[1]), sc[2]);
        rot_axis(axis, 6.28 * urand(&seed), R);
        for (i = 0; i < 3; ++i) {
            for (k = 0; k < 3; ++k)
                M[4 * i + k] = R[3 * i + k] * sc[k];
            M[4 * i + 3] = T[i];
        }
        obj = rt_scene_add_object(s, rt_scene_add_leaf(s, &plane_y, NULL, 0, M, mat));
        CHECK(rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
        for (k = 0; k < 500; ++k) {
            double o[3], d[3], len = pow(10.0, 6 * urand(&seed) - 3), oo[3], od[3], r[IG_MAX_DEGREE + 2];
            long double num = 0, den = 0, ts, mag = 0, magd = 0;
            rt_pending ph;
            int got, ng;
            for (i = 0; i < 3; ++i) {
                o[i] = T[i] + 40 * urand(&seed) - 20;
                d[i] = len * (2 * urand(&seed) - 1);
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
                /* t is off by the rounding of f(o) (relative to |o| + |T|) and of c1 (relative to the sum
                 * of |terms|: a grazing ray cancels), times the condition number of the transform (its
                 * inverse is rounded) */
                long double tol = 64 * DBL_EPSILON * cond * (mag + ts * magd) / fabsl(den);
                long double e = fabsl(ph.t - ts) / tol;
                CHECK(got && ph.object == obj, "plane path: no hit at t = %.17g", (double)ts);
                if (got) {
                    ++hits;
                    worst = (double)e > worst ? (double)e : worst;
                }
                if (ng > 0) {
                    double eg = (double)(fabsl(r[0] - ts) / tol);
                    worst_general = eg > worst_general ? eg : worst_general;
                    agree += got && fabs(r[0] - ph.t) <= (double)tol;
                }
            } else if (ts <= 0) {
                CHECK(!got, "plane path: a hit at t = %.17g behind the ray (plane at %.17g)", ph.t, (double)ts);
                ++misses;
            }
        }
        rt_scene_free(s);
    }
    CHECK(worst <= 1.0 && hits > 5000 && misses > 5000, "plane path: worst %.3g of tolerance, %d hits, %d misses",
          worst, hits, misses);
    CHECK(agree == hits, "plane path and general solve agree on %d of %d hits", agree, hits);
    /* parallel, on the plane, a tiny direction component: the general path's answer */
    {
        rt_scene *s = rt_scene_new();
        double o[3] = {0.3, 2.0, -1.0}, d[3] = {1.0, 0.0, 0.5}, on[3] = {0.3, 0.0, -1.0}, up[3] = {0.1, 1.0, 0};
        double tiny[3] = {1.0, -1e-310, 0.0};
        rt_pending ph;
        int mat = add_matte(s);
        rt_scene_add_object(s, rt_scene_add_leaf(s, &plane_y, NULL, 0, IDENTITY, mat));
        CHECK(rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
        CHECK(!rt_scene_closest(s, o, d, 0, INFINITY, RT_CLOSEST, -1, &ph), "a ray parallel to the plane hits it");
        CHECK(!rt_scene_closest(s, on, up, 0, INFINITY, RT_CLOSEST, -1, &ph), "a ray leaving the plane hits it");
        CHECK(!rt_scene_closest(s, on, d, 0, INFINITY, RT_CLOSEST, -1, &ph), "a ray inside the plane hits it");
        d[1] = -1.0;
        CHECK(rt_scene_closest(s, o, d, 0, INFINITY, RT_CLOSEST, -1, &ph) && ph.t == 2.0, "t = %.17g, not 2", ph.t);
        /* c1 = -1e-310 is subnormal: the general path's root at 2e310 lies beyond the scene's far limit */
        CHECK(!rt_scene_closest(s, o, tiny, 0, INFINITY, RT_CLOSEST, -1, &ph), "a hit beyond the far limit");
        rt_scene_free(s);
    }
    printf("plane path: %d hits within %.3g of the tolerance (general solve %.3g), %d misses\n", hits, worst,
           worst_general, misses);
}
