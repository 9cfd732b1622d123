/* Robustness of secondary-ray origins: how often a ray leaving a hit from rt_spawn_origin hits its own surface
 * again (self-hit) or skips the true next surface (miss), per shape and scale.
 *
 * For each shape in the table (tests/test_tracer_c.py writes it: every example shape with its default
 * params) and each scale 1e-3, 1e-1, 1, 1e1, 1e3 (a uniform scale with a random rotation and a translation
 * of the same order), random primary rays give hit points; from each hit two rays leave, one into the
 * outside hemisphere and one into the inside hemisphere, from rt_spawn_origin (tracer: offset by the hit's
 * error bound) and traced from t = 0. The reference is every root of f along the same line solved from the
 * hit point itself, where the polynomial is well conditioned: the root nearest 0 is the hit's own surface,
 * the next one in the ray's direction the true second hit.
 *
 *   self-hit : the tracer reports a hit within 1000 error bounds of the spawn point that is not the true
 *              second hit;
 *   miss     : a true second hit exists farther than the offset could skip (2 err / |cos|), and the tracer
 *              returns nothing or something farther;
 *   ambiguous: the true second hit lies inside the band the offset skips (a ray grazing a concave
 *              surface), or it is the first of a grazing pair of roots closer than 1e-4 of the object's
 *              size (a sliver the solvers cannot resolve); counted, not failed.
 *
 * Usage: tracer_offsets HITS_PER_SHAPE [SEED]. Prints one line per shape (tests/test_tracer_c.py judges).
 */
#include "tracer_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the table, from a generated glue file */
extern const ig_shape *const rt_test_shapes[];
extern const double rt_test_params[][8];
extern const int rt_test_nshapes;

static double urand(unsigned long long *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

static void unit_vector(unsigned long long *s, double v[3])
{
    double l;
    do {
        v[0] = 2 * urand(s) - 1;
        v[1] = 2 * urand(s) - 1;
        v[2] = 2 * urand(s) - 1;
        l = rt_dot(v, v);
    } while (l > 1.0 || l < 1e-6);
    l = sqrt(l);
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
}

static void random_rotation(unsigned long long *s, double R[9])
{
    /* Gram-Schmidt on two random vectors */
    double a[3], b[3], c[3], k;
    int i;
    unit_vector(s, a);
    unit_vector(s, b);
    k = rt_dot(a, b);
    for (i = 0; i < 3; ++i)
        b[i] -= k * a[i];
    k = sqrt(rt_dot(b, b));
    for (i = 0; i < 3; ++i)
        b[i] /= k;
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
    for (i = 0; i < 3; ++i) {
        R[3 * i] = a[i];
        R[3 * i + 1] = b[i];
        R[3 * i + 2] = c[i];
    }
}

typedef struct counts {
    long hits, rays, match, near, self, miss, extra, ambiguous, lost, any_checked, any_differ;
    double err_max, err_sum, near_max;
} counts;

static void run_scale(const ig_shape *shape, const double *params, double scale, long want, unsigned long long *seed,
                      counts *c)
{
    double R[9], M[12], box[6], centre[3], rad = 0.0, T[3], eye[3], up[3] = {0, 1, 0};
    double mat[RT_MATERIAL_DOUBLES] = {1, 1, 1, 0, 0, 0, 0, 0.1, 0.9, 0, 1, 0, 0, 1.5, 0, 0, 0, 0, 0};
    rt_scene *s = rt_scene_new();
    long attempts = 0, got = 0;
    int i, j, leaf;
    double far;
    if (!shape->bounds(params, box)) {
        for (i = 0; i < 3; ++i) {
            box[i] = -1.5;
            box[i + 3] = 1.5;
        }
    }
    for (i = 0; i < 3; ++i) {
        if (!isfinite(box[i]))
            box[i] = -1.5;
        if (!isfinite(box[i + 3]))
            box[i + 3] = 1.5;
        centre[i] = 0.5 * (box[i] + box[i + 3]);
        rad += 0.25 * (box[i + 3] - box[i]) * (box[i + 3] - box[i]);
    }
    rad = sqrt(rad);
    random_rotation(seed, R);
    for (i = 0; i < 3; ++i)
        T[i] = scale * (6 * urand(seed) - 3);
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j)
            M[4 * i + j] = scale * R[3 * i + j];
        M[4 * i + 3] = T[i];
        eye[i] = T[i] + scale * (i == 2 ? 5.0 : 0.0);
    }
    leaf = rt_scene_add_leaf(s, shape, params, shape->nparams, M, rt_scene_add_material(s, mat));
    rt_scene_add_object(s, leaf);
    rt_scene_set_camera(s, eye, T, up, 40);
    if (rt_scene_commit(s) != 0) {
        printf("commit failed: %s\n", rt_scene_error(s));
        exit(99);
    }
    far = rt_scene_far(s);
    while (got < want && attempts < 50 * want) {
        double oo[3], to[3], dob[3], o[3], d[3];
        rt_hit h;
        int side;
        ++attempts;
        unit_vector(seed, oo);
        for (i = 0; i < 3; ++i) {
            oo[i] = centre[i] + 3.0 * rad * oo[i];
            to[i] = box[i] + (box[i + 3] - box[i]) * urand(seed);
            dob[i] = to[i] - oo[i];
        }
        rt_xform_point(s->nodes[leaf].m, oo, o);
        rt_xform_vector(s->nodes[leaf].m, dob, d);
        if (!rt_scene_intersect(s, o, d, 0.0, INFINITY, &h))
            continue;
        ++got;
        ++c->hits;
        if (h.err / scale > c->err_max)
            c->err_max = h.err / scale;
        c->err_sum += h.err / scale;
        for (side = 0; side < 2; ++side) {
            double d2[3], q[3], od2[3], roots[IG_MAX_DEGREE], cosn, dl, D2 = -1.0, dist_tr = -1.0;
            int nr, k, self = -1, got2;
            rt_hit h2;
            unit_vector(seed, d2);
            if ((rt_dot(d2, h.n) < 0.0) != (side == 1))
                for (i = 0; i < 3; ++i)
                    d2[i] = -d2[i];
            cosn = fabs(rt_dot(d2, h.n));
            dl = sqrt(rt_dot(d2, d2));
            ++c->rays;
            /* reference: roots along the line through the object-space hit point */
            rt_xform_vector(s->nodes[leaf].minv, d2, od2);
            {
                /* solved on the unit object-space direction, then back to the world parameter */
                double L = sqrt(rt_dot(od2, od2));
                for (i = 0; i < 3; ++i)
                    od2[i] /= L;
                nr = ig_shape_roots(shape, params, h.po, od2, -4.0 * rad, far / dl * L, IG_ROOTS_AUTO, roots);
                for (k = 0; k < nr; ++k)
                    roots[k] /= L;
            }
            for (k = 0; k < nr; ++k)
                if (self < 0 || fabs(roots[k]) < fabs(roots[self]))
                    self = k;
            if (self < 0 || fabs(roots[self]) * dl > 1e-6 * scale) {
                ++c->lost; /* the reference cannot find the hit's own root: nothing to compare */
                continue;
            }
            if (self + 1 < nr)
                D2 = roots[self + 1] * dl;
            rt_spawn_origin(&h, d2, q);
            got2 = rt_scene_intersect(s, q, d2, 0.0, INFINITY, &h2);
            if (got2) {
                double v[3];
                for (i = 0; i < 3; ++i)
                    v[i] = h2.p[i] - h.p[i];
                dist_tr = sqrt(rt_dot(v, v));
            }
            { /* a shadow ray's yes/no query (RT_ANY_OPAQUE: the root may be left unrefined) says yes exactly when
               * the closest-hit query finds a hit, on the whole ray and on segments ending short of and past
               * the second hit */
                double ends[3] = {INFINITY, got2 ? 0.75 * h2.t : 1.0, got2 ? 1.25 * h2.t : 2.0};
                int e;
                for (e = 0; e < 3 && c->hits % 4 == 0; ++e) { /* on every 4th hit point: the test's time */
                    rt_pending pc, pa;
                    int hc = rt_scene_closest(s, q, d2, 0.0, ends[e], RT_CLOSEST, -1, &pc);
                    int ha = rt_scene_closest(s, q, d2, 0.0, ends[e], RT_ANY_OPAQUE, -1, &pa);
                    ++c->any_checked;
                    c->any_differ += hc != ha;
                }
            }
            if (D2 >= 0.0 && D2 * cosn < 2.0 * h.err) {
                ++c->ambiguous; /* the second hit lies inside the band the offset skips */
            } else if (D2 >= 0.0 && self + 2 < nr && (roots[self + 2] - roots[self + 1]) * dl < 1e-4 * scale &&
                       !(got2 && fabs(dist_tr - D2) <= 1e-6 * fmax(D2, scale))) {
                ++c->ambiguous; /* a grazing pair of roots closer than 1e-4 of the object's size: whether the ray
                                   clips that sliver of inside is below what the solvers resolve */
            } else if (got2 && D2 >= 0.0 && fabs(dist_tr - D2) <= 1e-6 * fmax(D2, scale)) {
                ++c->match;
            } else if (!got2 && D2 < 0.0) {
                ++c->match;
            } else if (got2 && D2 >= 0.0 && fabs(dist_tr - D2) <= 1e-3 * fmax(D2, scale)) {
                /* the same crossing, located less precisely (near a singular point both solves lose digits) */
                ++c->near;
                if (fabs(dist_tr - D2) / fmax(D2, scale) > c->near_max)
                    c->near_max = fabs(dist_tr - D2) / fmax(D2, scale);
            } else if (got2 && dist_tr < 1000.0 * h.err) {
                ++c->self;
                if (c->self <= 3) {
                    printf("  self-hit: %s scale %g side %d dist %.3g err %.3g cos %.3g\n", shape->name, scale, side,
                           dist_tr, h.err, cosn);
#ifdef RT_DEBUG_OFFSETS
                    {
                        double g[3], g2[3];
                        shape->gradient(h.po, params, g);
                        shape->gradient(h2.po, params, g2);
                        printf("    hit po (%.17g %.17g %.17g) f %.3g |g| %.3g; h2 t %.3g po (%.17g %.17g %.17g) f "
                               "%.3g |g| %.3g"
                               " leaf %d; roots:",
                               h.po[0], h.po[1], h.po[2], shape->value(h.po, params), sqrt(rt_dot(g, g)), h2.t,
                               h2.po[0], h2.po[1], h2.po[2], shape->value(h2.po, params), sqrt(rt_dot(g2, g2)),
                               h2.leaf);
                        for (k = 0; k < nr; ++k)
                            printf(" %.6g", roots[k] * dl);
                        printf("\n");
                    }
#endif
                }
            } else if (D2 >= 0.0 && (!got2 || dist_tr > D2)) {
                ++c->miss;
                if (c->miss <= 3) {
                    printf("  miss: %s scale %g side %d true %.6g got %.6g err %.3g cos %.3g\n", shape->name, scale,
                           side, D2, got2 ? dist_tr : -1.0, h.err, cosn);
#ifdef RT_DEBUG_OFFSETS
                    printf("    reference roots:");
                    for (k = 0; k < nr; ++k)
                        printf(" %.9g", roots[k] * dl);
                    printf("\n");
#endif
                }
            } else {
                ++c->extra;
                if (c->extra <= 3) {
                    printf("  disagreement: %s scale %g side %d true %.6g got %.6g err %.3g cos %.3g\n", shape->name,
                           scale, side, D2, got2 ? dist_tr : -1.0, h.err, cosn);
#ifdef RT_DEBUG_OFFSETS
                    {
                        double g[3];
                        shape->gradient(h2.po, params, g);
                        printf("    f(tracer hit) %.3g |grad| %.3g; reference roots:", shape->value(h2.po, params),
                               sqrt(rt_dot(g, g)));
                        for (k = 0; k < nr; ++k)
                            printf(" %.6g", roots[k] * dl);
                        printf("\n");
                    }
#endif
                }
            }
        }
    }
    rt_scene_free(s);
}

int main(int argc, char **argv)
{
    long per_shape = argc > 1 ? atol(argv[1]) : 1000;
    unsigned long long seed = argc > 2 ? strtoull(argv[2], NULL, 10) : 12345ULL;
    double scales[5] = {1e-3, 1e-1, 1.0, 1e1, 1e3};
    long fails = 0;
    int k, j;
    for (k = 0; k < rt_test_nshapes; ++k) {
        counts c;
        memset(&c, 0, sizeof c);
        for (j = 0; j < 5; ++j)
            run_scale(rt_test_shapes[k], rt_test_params[k], scales[j], per_shape / 5, &seed, &c);
        printf("%-10s hits %7ld rays %7ld match %7ld self-hits %ld misses %ld other %ld ambiguous %ld lost %ld "
               "near %ld (worst %.1e) err/scale max %.2e mean %.2e any-opaque %ld differ %ld\n",
               rt_test_shapes[k]->name, c.hits, c.rays, c.match, c.self, c.miss, c.extra, c.ambiguous, c.lost, c.near,
               c.near_max, c.err_max, c.hits ? c.err_sum / c.hits : 0.0, c.any_checked, c.any_differ);
        fails += c.self + c.miss;
    }
    printf("%ld failures\n", fails);
    return 0; /* the pytest side judges the counts; a sanitizer error still exits non-zero */
}
