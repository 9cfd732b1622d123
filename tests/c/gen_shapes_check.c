/* Sanitizer driver for the generated shapes: random rays through every example shape's generated
 * intersect/normal, compiled with -fsanitize=address,undefined by tests/test_generated_c.py.
 *
 * For each root t we check the backward error: |p(t)| <= tol * sum_k |c_k| |t|^k with the coefficients
 * at the ray's own origin, that roots ascend inside [tmin, tmax], and that normals are unit or exactly zero
 * (singular point), never NaN. The shape table comes from a generated header (GEN_SHAPES_TABLE). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "gen_shapes_table.h"

static double uniform(unsigned long long *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) / 9007199254740992.0;
}

static int check_shape(const ig_shape *shape, const double *params, int rays, int *failures)
{
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
        for (int k = 0; k < n; ++k) {
            double t = roots[k], value = 0.0, scale = 0.0, n3[3];
            for (int j = shape->degree; j >= 0; --j) {
                value = value * t + c[j];
                scale = scale * fabs(t) + fabs(c[j]);
            }
            double p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
            int ok_normal = ig_shape_normal(shape, params, p, n3);
            double len = sqrt(n3[0] * n3[0] + n3[1] * n3[1] + n3[2] * n3[2]);
            int bad = !(t >= 0.0 && t <= 1e3) || (k > 0 && !(t > roots[k - 1])) || !isfinite(t)
                      || fabs(value) > 1e-9 * scale
                      || (ok_normal ? fabs(len - 1.0) > 1e-12 : len != 0.0);
            if (bad) {
                if (*failures < 10)
                    fprintf(stderr, "%s ray %d root %d: t=%.17g |p(t)|=%.3g scale=%.3g |n|=%.17g\n", shape->name,
                            r, k, t, fabs(value), scale, len);
                ++*failures;
            }
        }
    }
    return hits;
}

int main(void)
{
    int failures = 0, passed = 0;
    for (size_t s = 0; s < sizeof gen_shapes / sizeof gen_shapes[0]; ++s) {
        int before = failures;
        int hits = check_shape(gen_shapes[s].shape, gen_shapes[s].params, 20000, &failures);
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
