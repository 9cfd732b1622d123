/* Sanitizer driver for the generated shapes: random rays through every example shape's generated
 * intersect/first_hit/normal, compiled with -fsanitize=address,undefined by tests/test_generated_c.py; one named
 * case per shape (tests/c/ctest.h), each reported to pytest by name.
 *
 * For each root t we check the backward error: |p(t)| <= tol * sum_k |c_k| |t|^k with the coefficients
 * at the ray's own origin, that roots ascend inside [tmin, tmax], and that normals are unit or exactly zero
 * (singular point), never NaN. <name>_intersect must give exactly ig_shape_roots' answer, and <name>_first_hit
 * a hit exactly when intersect has one (leaving t alone on a miss), with bitwise the same root (the
 * first-root search visits the same pieces as the full one; a difference is counted, printed and fails).
 * The shapes come from a generated header (gen_shapes_table.h, written by the test): each shape's header and
 * default params (params_<name>), and GEN_SHAPES(X), X(name) for each shape. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctest.h"
#include "gen_shapes_table.h"

typedef int (*gen_ray_fn)(const double o[3], const double d[3], double tmin, double tmax, const double *params,
                          double *t);

typedef struct {
    const ig_shape *shape;
    const double *params;
    gen_ray_fn intersect, first_hit;
} gen_shape_entry;

enum { RAYS = 20000, MIN_HITS = 1000, SHOWN = 10 };

/* One failure more; its message only for the first SHOWN of a case (a broken shape fails on thousands of rays). */
#define FAIL_SHOWN(t, ...)                                                                                             \
    do {                                                                                                               \
        if ((t)->failures < SHOWN)                                                                                     \
            ctest_fail((t), __VA_ARGS__);                                                                              \
        else                                                                                                           \
            ++(t)->failures;                                                                                           \
    } while (0)

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

/* How first_hit compared with intersect()[0] on a shape's rays. */
typedef struct {
    int differ;
    double max_rel;
} first_tally;

/* first_hit against intersect on one ray: 0 when consistent; counts differences */
static int check_first_hit(const gen_shape_entry *e, const double o[3], const double d[3], const double *roots, int n,
                           first_tally *ft)
{
    double t = -12345.0;
    int got = e->first_hit(o, d, 0.0, 1e3, e->params, &t);
    if (got != (n > 0))
        return 1;
    if (!got)
        return t != -12345.0;
    if (t == roots[0])
        return 0;
    ++ft->differ;
    double rel = fabs(t - roots[0]) / fmax(fabs(roots[0]), 1e-300);
    if (rel > ft->max_rel)
        ft->max_rel = rel;
    return 1;
}

/* A random ray from around the shape's box towards a point in it, with a non-unit direction. */
static void random_ray(unsigned long long *rng, const double box[6], double o[3], double d[3])
{
    for (int i = 0; i < 3; ++i) {
        double lo = isfinite(box[i]) ? box[i] : -2.0, hi = isfinite(box[i + 3]) ? box[i + 3] : 2.0;
        double target = lo + (hi - lo) * uniform(rng);
        o[i] = 6.0 * (uniform(rng) - 0.5) + target;
        d[i] = target;
    }
    for (int i = 0; i < 3; ++i)
        d[i] = (d[i] - o[i]) * (0.1 + 3.0 * uniform(rng)); /* non-unit direction towards the box */
}

/* Each root of ray r: inside [0, 1e3], ascending, a small backward error, a unit or zero normal. */
static void check_roots(ctest *t, const gen_shape_entry *e, int r, const double o[3], const double d[3],
                        const double *roots, int n)
{
    double c[IG_MAX_DEGREE + 1];
    e->shape->coeffs(o, d, e->params, c);
    for (int k = 0; k < n; ++k) {
        double tk = roots[k], scale, n3[3];
        double value = backward(c, e->shape->degree, tk, &scale);
        double p[3] = {o[0] + tk * d[0], o[1] + tk * d[1], o[2] + tk * d[2]};
        int ok_normal = ig_shape_normal(e->shape, e->params, p, n3);
        double len = sqrt(n3[0] * n3[0] + n3[1] * n3[1] + n3[2] * n3[2]);
        int bad = !(tk >= 0.0 && tk <= 1e3) || (k > 0 && !(tk > roots[k - 1])) || !isfinite(tk) ||
                  value > 1e-9 * scale || (ok_normal ? fabs(len - 1.0) > 1e-12 : len != 0.0);
        if (bad)
            FAIL_SHOWN(t, "%s ray %d root %d: t=%.17g |p(t)|=%.3g scale=%.3g |n|=%.17g", e->shape->name, r, k, tk,
                       value, scale, len);
    }
}

/* RAYS random rays through one shape: intersect exactly ig_shape_roots, first_hit its first root, every root
 * checked; and enough of them hit for the test to mean anything. */
static void check_shape(ctest *t, const gen_shape_entry *e)
{
    unsigned long long rng = 12345u;
    first_tally ft = {0, 0.0};
    double box[6];
    int hits = 0;
    e->shape->bounds(e->params, box);
    for (int r = 0; r < RAYS; ++r) {
        double o[3], d[3], roots[IG_MAX_DEGREE], gen[IG_MAX_DEGREE];
        random_ray(&rng, box, o, d);
        int n = ig_shape_roots(e->shape, e->params, o, d, 0.0, 1e3, IG_ROOTS_AUTO, roots);
        hits += n > 0;
        int ng = e->intersect(o, d, 0.0, 1e3, e->params, gen);
        int bad_gen = ng != n || (n > 0 && memcmp(gen, roots, (size_t)n * sizeof *roots) != 0);
        if (bad_gen || check_first_hit(e, o, d, roots, n, &ft)) {
            double tf = NAN;
            int got = e->first_hit(o, d, 0.0, 1e3, e->params, &tf);
            FAIL_SHOWN(t, "%s ray %d: intersect %d roots (ig_shape_roots %d), first %.17g; first_hit %d: %.17g",
                       e->shape->name, r, ng, n, n > 0 ? roots[0] : NAN, got, tf);
        }
        check_roots(t, e, r, o, d, roots, n);
    }
    printf("%-10s first_hit != intersect()[0] on %d rays (max rel difference %.1e)\n", e->shape->name, ft.differ,
           ft.max_rel);
    printf("%-10s %5d of %d rays hit\n", e->shape->name, hits, RAYS);
    CHECKF(t, hits >= MIN_HITS, "%s: too few hits (%d) for the test to mean anything", e->shape->name, hits);
}

/* one case per shape, named after it */
#define GEN_CASE_FN(name)                                                                                              \
    static void case_##name(ctest *t)                                                                                  \
    {                                                                                                                  \
        const gen_shape_entry e = {&name##_shape, params_##name, name##_intersect, name##_first_hit};                  \
        check_shape(t, &e);                                                                                            \
    }
GEN_SHAPES(GEN_CASE_FN)

#define GEN_CASE_ROW(name) {#name, case_##name},
static const ctest_case CASES[] = {GEN_SHAPES(GEN_CASE_ROW)};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
