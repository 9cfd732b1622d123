/* ig_shape_roots_many and ig_shape_eval_many (runtime_c/shape_batch.c) against the single-ray and single-point
 * calls, bit for bit, on the torus fixture: rays through, grazing, parallel to an axis, missing the box, with
 * empty and reversed intervals. ig_shape_project_many against the torus' distance in closed form (the mesh's
 * own loops: tests/c/test_mesh_kernels.c). Built with ASan + UBSan by tests/test_c_drivers_roots.py. */
#include "shape_batch.h"
#include "shape_torus_fixture.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NRAYS 400

/* Distance of p to the torus of the fixture (axis y, radii a, b), in closed form. */
static double torus_distance(const double p[3], double a, double b)
{
    double rho = sqrt(p[0] * p[0] + p[2] * p[2]) - a;
    return fabs(sqrt(rho * rho + p[1] * p[1]) - b);
}

static int check_projection(const double params[2])
{
    enum { N = 64 };
    double p[3 * N], start[3 * N];
    unsigned char ok[N];
    int failures = 0;
    for (int i = 0; i < N; ++i) { /* points within a tenth of the tube's radius of the surface, all around */
        double u = 6.283185307179586 * i / N, v = 2.399963229728653 * i, r = 0.25 + 0.025 * sin(5.0 * i);
        start[3 * i] = (1.0 + r * cos(v)) * cos(u);
        start[3 * i + 1] = r * sin(v);
        start[3 * i + 2] = (1.0 + r * cos(v)) * sin(u);
    }
    start[0] = start[1] = start[2] = 0.0; /* the centre: grad f = 0 there, no step to take */
    memcpy(p, start, sizeof p);
    ig_shape_project_many(&shape_torus_fixture, params, N, p, 40, 1e-13, 1e-10, 1e-3, ok);
    for (int i = 1; i < N; ++i)
        if (ok[i] != 0 && torus_distance(start + 3 * i, 1.0, 0.25) > 2e-3) { /* had to go further than reach */
            printf("point %d: projected, beyond the reach\n", i);
            ++failures;
        }
    memcpy(p, start, sizeof p);
    ig_shape_project_many(&shape_torus_fixture, params, N, p, 40, 1e-13, 1e-10, 0.1, ok);
    if (ok[0] != 0 || memcmp(p, start, 3 * sizeof *p) != 0) {
        printf("the centre of the torus: projected (%d) or moved\n", ok[0]);
        ++failures;
    }
    for (int i = 1; i < N; ++i)
        if (ok[i] != 1 || torus_distance(p + 3 * i, 1.0, 0.25) > 1e-14) {
            printf("point %d: ok %d, %.3g from the torus\n", i, ok[i], torus_distance(p + 3 * i, 1.0, 0.25));
            ++failures;
        }
    return failures;
}

int main(void)
{
    const double params[2] = {1.0, 0.25};
    double *o = malloc(3 * NRAYS * sizeof *o), *d = malloc(3 * NRAYS * sizeof *d);
    double *t0 = malloc(NRAYS * sizeof *t0), *t1 = malloc(NRAYS * sizeof *t1);
    double *roots = malloc((size_t)NRAYS * IG_MAX_DEGREE * sizeof *roots);
    int *counts = malloc(NRAYS * sizeof *counts);
    double *f = malloc(NRAYS * sizeof *f), *g = malloc(3 * NRAYS * sizeof *g);
    int failures = 0, total = 0;
    if (!o || !d || !t0 || !t1 || !roots || !counts || !f || !g)
        return 2;
    for (int i = 0; i < NRAYS; ++i) {
        double u = -1.5 + 3.0 * i / (NRAYS - 1.0);
        int axis = i % 3;
        for (int k = 0; k < 3; ++k) {
            o[3 * i + k] = (k == axis) ? -2.0 : u * (k == (axis + 1) % 3 ? 1.0 : 0.07);
            d[3 * i + k] = (k == axis) ? 1.0 : 0.0;
        }
        if (i % 7 == 0) /* an oblique ray */
            d[3 * i + (axis + 1) % 3] = 0.3;
        t0[i] = (i % 11 == 0) ? 5.0 : 0.0; /* some intervals reversed: no roots */
        t1[i] = (i % 13 == 0) ? INFINITY : 4.0;
    }
    o[3 * 5 + 1] = 0.25; /* grazing the tube's top along x */
    o[3 * 5 + 2] = 0.0;
    ig_shape_roots_many(&shape_torus_fixture, params, NRAYS, o, d, t0, t1, IG_ROOTS_AUTO, roots, counts);
    ig_shape_eval_many(&shape_torus_fixture, params, NRAYS, o, f, g);
    for (int i = 0; i < NRAYS; ++i) {
        double one[IG_MAX_DEGREE];
        int n = ig_shape_roots(&shape_torus_fixture, params, o + 3 * i, d + 3 * i, t0[i], t1[i], IG_ROOTS_AUTO, one);
        total += n;
        if (n != counts[i] || memcmp(one, roots + (size_t)i * IG_MAX_DEGREE, (size_t)n * sizeof *one) != 0) {
            printf("ray %d: %d roots one by one, %d in the batch\n", i, n, counts[i]);
            ++failures;
        }
        double gi[3];
        double fi = shape_torus_fixture.value(o + 3 * i, params);
        shape_torus_fixture.gradient(o + 3 * i, params, gi);
        if (memcmp(&fi, f + i, sizeof fi) != 0 || memcmp(gi, g + 3 * i, sizeof gi) != 0) {
            printf("point %d: value or gradient differs\n", i);
            ++failures;
        }
    }
    ig_shape_eval_many(&shape_torus_fixture, params, NRAYS, o, f, NULL); /* values only */
    for (int i = 0; i < NRAYS; ++i) {
        double fi = shape_torus_fixture.value(o + 3 * i, params);
        if (memcmp(&fi, f + i, sizeof fi) != 0) {
            printf("point %d: the value alone differs\n", i);
            ++failures;
        }
    }
    failures += check_projection(params);
    {
        const double gx[3] = {-1.0, 0.1, 1.3}, gy[2] = {-0.2, 0.05}, gz[4] = {-0.3, 0.0, 0.125, 2.0};
        double gv[24];
        ig_shape_values_grid(&shape_torus_fixture, params, gx, 3, gy, 2, gz, 4, gv);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 2; ++j)
                for (int k = 0; k < 4; ++k) {
                    double p[3] = {gx[i], gy[j], gz[k]};
                    double v = shape_torus_fixture.value(p, params);
                    if (memcmp(&v, gv + (i * 2 + j) * 4 + k, sizeof v) != 0) {
                        printf("grid point (%d, %d, %d) differs\n", i, j, k);
                        ++failures;
                    }
                }
    }
    ig_shape_roots_many(&shape_torus_fixture, params, 0, o, d, t0, t1, IG_ROOTS_AUTO, roots, counts);
    free(o);
    free(d);
    free(t0);
    free(t1);
    free(roots);
    free(counts);
    free(f);
    free(g);
    if (failures || total < NRAYS) {
        printf("%d failures, %d roots\n", failures, total);
        return 1;
    }
    printf("all batch checks passed (%d roots)\n", total);
    return 0;
}
