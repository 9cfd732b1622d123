/* Sanitizer driver for the generated shapes: random rays through every example shape's generated
 * intersect/first_hit/normal, compiled with -fsanitize=address,undefined by tests/test_generated_c.py.
 *
 * For each root t we check the backward error: |p(t)| <= tol * sum_k |c_k| |t|^k with the coefficients
 * at the ray's own origin, that roots ascend inside [tmin, tmax], and that normals are unit or exactly zero
 * (singular point), never NaN. <name>_intersect must give exactly ig_shape_roots' answer, and <name>_first_hit
 * a hit exactly when intersect has one (leaving t alone on a miss), with bitwise the same root (the
 * first-root search visits the same pieces as the full one; a difference is counted, printed and fails).
 * The shape table comes from a generated
 * header (gen_shapes_table.h, written by the test). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gen_shapes_table.h"

static double uniform(unsigned long long *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) / 9007199254740992.0;
}

/* |p(t)| and sum_k |c_k| |t|^k */
static double backward(const double *c, int degree, double t, double *scale)
{
    double value = 0.0;
    *scale = 0.0;
    for (int j = degree; j >= 0; --j) {
        value = value * t + c[j];
        *scale = *scale * fabs(t) + fabs(c[j]);
    }
    return fabs(value);
}

/* first_hit against intersect on one ray: 0 when consistent; counts differences in *differ */
static int check_first_hit(const gen_shape_entry *e, const double o[3], const double d[3], const double *roots, int n,
                           int *differ, double *max_rel)
{
    double t = -12345.0;
    int got = e->first_hit(o, d, 0.0, 1e3, e->params, &t);
    if (got != (n > 0))
        return 1;
    if (!got)
        return t != -12345.0;
    if (t == roots[0])
        return 0;
    ++*differ;
    double rel = fabs(t - roots[0]) / fmax(fabs(roots[0]), 1e-300);
    if (rel > *max_rel)
        *max_rel = rel;
    return 1;
}

static int check_shape(const gen_shape_entry *e, int rays, int *failures)
{
    const ig_shape *shape = e->shape;
    const double *params = e->params;
    int differ = 0;
    double max_rel = 0.0;
    unsigned long long rng = 12345u;
    double box[6];
    int hits = 0;
    shape->bounds(params, box);
    for (int r = 0; r < rays; ++r) {
        double o[3], d[3], roots[IG_MAX_DEGREE], c[IG_MAX_DEGREE + 1];
        for (int i = 0; i < 3; ++i) {
            double lo = isfinite(box[i]) ? box[i] : -2.0, hi = isfinite(box[i + 3]) ? box[i + 3] : 2.0;
            double target = lo + (hi - lo) * uniform(&rng);
            o[i] = 6.0 * (uniform(&rng) - 0.5) + target;
            d[i] = target;
        }
        for (int i = 0; i < 3; ++i)
            d[i] = (d[i] - o[i]) * (0.1 + 3.0 * uniform(&rng)); /* non-unit direction towards the box */
        int n = ig_shape_roots(shape, params, o, d, 0.0, 1e3, IG_ROOTS_AUTO, roots);
        shape->coeffs(o, d, params, c);
        hits += n > 0;
        double gen[IG_MAX_DEGREE];
        int ng = e->intersect(o, d, 0.0, 1e3, params, gen);
        int bad_gen = ng != n || (n > 0 && memcmp(gen, roots, (size_t)n * sizeof *roots) != 0);
        if (bad_gen || check_first_hit(e, o, d, roots, n, &differ, &max_rel)) {
            double t = NAN;
            int got = e->first_hit(o, d, 0.0, 1e3, params, &t);
            if (*failures < 10)
                fprintf(stderr,
                        "%s ray %d: intersect %d roots (ig_shape_roots %d), first %.17g; first_hit %d: "
                        "%.17g\n",
                        shape->name, r, ng, n, n > 0 ? roots[0] : NAN, got, t);
            ++*failures;
        }
        for (int k = 0; k < n; ++k) {
            double t = roots[k], scale, n3[3];
            double value = backward(c, shape->degree, t, &scale);
            double p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
            int ok_normal = ig_shape_normal(shape, params, p, n3);
            double len = sqrt(n3[0] * n3[0] + n3[1] * n3[1] + n3[2] * n3[2]);
            int bad = !(t >= 0.0 && t <= 1e3) || (k > 0 && !(t > roots[k - 1])) || !isfinite(t) ||
                      value > 1e-9 * scale || (ok_normal ? fabs(len - 1.0) > 1e-12 : len != 0.0);
            if (bad) {
                if (*failures < 10)
                    fprintf(stderr, "%s ray %d root %d: t=%.17g |p(t)|=%.3g scale=%.3g |n|=%.17g\n", shape->name, r, k,
                            t, value, scale, len);
                ++*failures;
            }
        }
    }
    printf("%-10s first_hit != intersect()[0] on %d rays (max rel difference %.1e)\n", shape->name, differ, max_rel);
    return hits;
}

int main(void)
{
    int failures = 0, passed = 0;
    for (size_t s = 0; s < sizeof gen_shapes / sizeof gen_shapes[0]; ++s) {
        int before = failures;
        int hits = check_shape(&gen_shapes[s], 20000, &failures);
        printf("%-10s %5d of 20000 rays hit\n", gen_shapes[s].shape->name, hits);
        if (hits < 1000) {
            fprintf(stderr, "%s: too few hits (%d) for the test to mean anything\n", gen_shapes[s].shape->name, hits);
            ++failures;
        }
        passed += failures == before;
    }
    printf("%d passed, %d failed\n", passed, failures ? 1 : 0);
    return failures ? 1 : 0;
}
