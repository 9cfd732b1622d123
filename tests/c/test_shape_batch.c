/* ig_shape_roots_many and ig_shape_eval_many (runtime_c/shape_batch.c) against the single-ray and single-point
 * calls, bit for bit, on the torus fixture: rays through, grazing, parallel to an axis, missing the box, with
 * empty and reversed intervals. ig_shape_project_many against the torus' distance in closed form (the mesh's
 * own loops: tests/c/test_mesh_kernels.c). Named cases (tests/c/ctest.h), built with ASan + UBSan by
 * tests/test_c_drivers_roots.py and each reported by name. */
#include "shape_batch.h"
#include "shape_torus_fixture.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctest.h"

#define NRAYS 400

static const double PARAMS[2] = {1.0, 0.25};

/* NRAYS rays (origins o, directions d, intervals [t0, t1]) and room for what the batch calls write. */
typedef struct {
    double *o, *d, *t0, *t1, *roots, *f, *g;
    int *counts;
} batch;

static void batch_free(batch *b)
{
    free(b->o);
    free(b->d);
    free(b->t0);
    free(b->t1);
    free(b->roots);
    free(b->counts);
    free(b->f);
    free(b->g);
}

/* The rays along the three axes across the torus, every 7th oblique, some intervals reversed or unbounded, one
 * grazing the tube's top; 0 when out of memory. */
static int batch_new(batch *b)
{
    b->o = malloc(3 * NRAYS * sizeof *b->o);
    b->d = malloc(3 * NRAYS * sizeof *b->d);
    b->t0 = malloc(NRAYS * sizeof *b->t0);
    b->t1 = malloc(NRAYS * sizeof *b->t1);
    b->roots = malloc((size_t)NRAYS * IG_MAX_DEGREE * sizeof *b->roots);
    b->counts = malloc(NRAYS * sizeof *b->counts);
    b->f = malloc(NRAYS * sizeof *b->f);
    b->g = malloc(3 * NRAYS * sizeof *b->g);
    if (!b->o || !b->d || !b->t0 || !b->t1 || !b->roots || !b->counts || !b->f || !b->g)
        return 0;
    for (int i = 0; i < NRAYS; ++i) {
        double u = -1.5 + 3.0 * i / (NRAYS - 1.0);
        int axis = i % 3;
        for (int k = 0; k < 3; ++k) {
            b->o[3 * i + k] = (k == axis) ? -2.0 : u * (k == (axis + 1) % 3 ? 1.0 : 0.07);
            b->d[3 * i + k] = (k == axis) ? 1.0 : 0.0;
        }
        if (i % 7 == 0) /* an oblique ray */
            b->d[3 * i + (axis + 1) % 3] = 0.3;
        b->t0[i] = (i % 11 == 0) ? 5.0 : 0.0; /* some intervals reversed: no roots */
        b->t1[i] = (i % 13 == 0) ? INFINITY : 4.0;
    }
    b->o[3 * 5 + 1] = 0.25; /* grazing the tube's top along x */
    b->o[3 * 5 + 2] = 0.0;
    return 1;
}

/* every ray's roots in the batch bitwise those of ig_shape_roots; an empty batch touches nothing */
static void roots_many_equals_one_by_one(ctest *t)
{
    batch b;
    int total = 0;
    if (CHECK(t, batch_new(&b))) {
        ig_shape_roots_many(&shape_torus_fixture, PARAMS, NRAYS, b.o, b.d, b.t0, b.t1, IG_ROOTS_AUTO, b.roots,
                            b.counts);
        for (int i = 0; i < NRAYS; ++i) {
            double one[IG_MAX_DEGREE];
            int n = ig_shape_roots(&shape_torus_fixture, PARAMS, b.o + 3 * i, b.d + 3 * i, b.t0[i], b.t1[i],
                                   IG_ROOTS_AUTO, one);
            total += n;
            CHECKF(t,
                   n == b.counts[i] && memcmp(one, b.roots + (size_t)i * IG_MAX_DEGREE, (size_t)n * sizeof *one) == 0,
                   "ray %d: %d roots one by one, %d in the batch", i, n, b.counts[i]);
        }
        ig_shape_roots_many(&shape_torus_fixture, PARAMS, 0, b.o, b.d, b.t0, b.t1, IG_ROOTS_AUTO, b.roots, b.counts);
        CHECKF(t, total >= NRAYS, "%d roots, want at least one a ray", total);
        printf("batch roots: %d\n", total);
    }
    batch_free(&b);
}

/* f and its gradient at every ray origin, bitwise the shape's own value and gradient */
static void eval_many_equals_value_and_gradient(ctest *t)
{
    batch b;
    if (CHECK(t, batch_new(&b))) {
        ig_shape_eval_many(&shape_torus_fixture, PARAMS, NRAYS, b.o, b.f, b.g);
        for (int i = 0; i < NRAYS; ++i) {
            double gi[3];
            double fi = shape_torus_fixture.value(b.o + 3 * i, PARAMS);
            shape_torus_fixture.gradient(b.o + 3 * i, PARAMS, gi);
            CHECKF(t, memcmp(&fi, b.f + i, sizeof fi) == 0 && memcmp(gi, b.g + 3 * i, sizeof gi) == 0,
                   "point %d: value or gradient differs", i);
        }
    }
    batch_free(&b);
}

/* the values alone (no gradient asked for) */
static void eval_many_values_alone(ctest *t)
{
    batch b;
    if (CHECK(t, batch_new(&b))) {
        ig_shape_eval_many(&shape_torus_fixture, PARAMS, NRAYS, b.o, b.f, NULL);
        for (int i = 0; i < NRAYS; ++i) {
            double fi = shape_torus_fixture.value(b.o + 3 * i, PARAMS);
            CHECKF(t, memcmp(&fi, b.f + i, sizeof fi) == 0, "point %d: the value alone differs", i);
        }
    }
    batch_free(&b);
}

/* Distance of p to the torus of the fixture (axis y, radii a, b), in closed form. */
static double torus_distance(const double p[3], double a, double b)
{
    double rho = sqrt(p[0] * p[0] + p[2] * p[2]) - a;
    return fabs(sqrt(rho * rho + p[1] * p[1]) - b);
}

enum { NPOINTS = 64 };

/* points within a tenth of the tube's radius of the surface, all around; the first the centre, where grad f = 0
 * and there is no step to take */
static void near_points(double start[3 * NPOINTS])
{
    for (int i = 0; i < NPOINTS; ++i) {
        double u = 6.283185307179586 * i / NPOINTS, v = 2.399963229728653 * i, r = 0.25 + 0.025 * sin(5.0 * i);
        start[3 * i] = (1.0 + r * cos(v)) * cos(u);
        start[3 * i + 1] = r * sin(v);
        start[3 * i + 2] = (1.0 + r * cos(v)) * sin(u);
    }
    start[0] = start[1] = start[2] = 0.0;
}

/* with a reach of 1e-3, no point projected that had to go further */
static void project_many_stays_within_its_reach(ctest *t)
{
    double p[3 * NPOINTS], start[3 * NPOINTS];
    unsigned char ok[NPOINTS];
    near_points(start);
    memcpy(p, start, sizeof p);
    ig_shape_project_many(&shape_torus_fixture, PARAMS, NPOINTS, p, 40, 1e-13, 1e-10, 1e-3, ok);
    for (int i = 1; i < NPOINTS; ++i)
        CHECKF(t, !(ok[i] != 0 && torus_distance(start + 3 * i, 1.0, 0.25) > 2e-3),
               "point %d: projected, beyond the reach", i);
}

/* with a reach of 0.1, every point but the centre lands on the torus; the centre stays where it is */
static void project_many_lands_on_the_torus_and_leaves_the_centre(ctest *t)
{
    double p[3 * NPOINTS], start[3 * NPOINTS];
    unsigned char ok[NPOINTS];
    near_points(start);
    memcpy(p, start, sizeof p);
    ig_shape_project_many(&shape_torus_fixture, PARAMS, NPOINTS, p, 40, 1e-13, 1e-10, 0.1, ok);
    CHECKF(t, !(ok[0] != 0 || memcmp(p, start, 3 * sizeof *p) != 0), "the centre of the torus: projected (%d) or moved",
           ok[0]);
    for (int i = 1; i < NPOINTS; ++i)
        CHECKF(t, !(ok[i] != 1 || torus_distance(p + 3 * i, 1.0, 0.25) > 1e-14), "point %d: ok %d, %.3g from the torus",
               i, ok[i], torus_distance(p + 3 * i, 1.0, 0.25));
}

/* f over a 3 x 2 x 4 grid, bitwise f at each point */
static void values_grid_equals_the_value_at_each_point(ctest *t)
{
    const double gx[3] = {-1.0, 0.1, 1.3}, gy[2] = {-0.2, 0.05}, gz[4] = {-0.3, 0.0, 0.125, 2.0};
    double gv[24];
    ig_shape_values_grid(&shape_torus_fixture, PARAMS, gx, 3, gy, 2, gz, 4, gv);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 4; ++k) {
                double p[3] = {gx[i], gy[j], gz[k]};
                double v = shape_torus_fixture.value(p, PARAMS);
                CHECKF(t, memcmp(&v, gv + (i * 2 + j) * 4 + k, sizeof v) == 0, "grid point (%d, %d, %d) differs", i, j,
                       k);
            }
}

static const ctest_case CASES[] = {
    CTEST_CASE(roots_many_equals_one_by_one),
    CTEST_CASE(eval_many_equals_value_and_gradient),
    CTEST_CASE(eval_many_values_alone),
    CTEST_CASE(project_many_stays_within_its_reach),
    CTEST_CASE(project_many_lands_on_the_torus_and_leaves_the_centre),
    CTEST_CASE(values_grid_equals_the_value_at_each_point),
};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
