/* ig_shape_roots_many and ig_shape_eval_many (runtime_c/shape_batch.c) against the single-ray and single-point
 * calls, bit for bit, on the torus fixture: rays through, grazing, parallel to an axis, missing the box, with
 * empty and reversed intervals. ig_shape_project_many against the torus' distance in closed form; the mesh
 * helpers (ig_mesh_sheet_points, ig_mesh_split_quads) on one cell cut by a plane and by a crease, whose dual
 * points are known, and on a quad whose shorter diagonal is known. Built with ASan + UBSan by
 * tests/test_c_drivers_roots.py. */
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

static int near3(const double *p, double x, double y, double z)
{
    return fabs(p[0] - x) < 1e-12 && fabs(p[1] - y) < 1e-12 && fabs(p[2] - z) < 1e-12;
}

/* The unit cell [0, 1]^3 of a grid of 2 x 2 x 2 vertices (strides 4, 2, 1). First cut by the plane z = 0.3 (four
 * edges along z, one sheet: its point is the crossings' mass point); then the crease x < 0.4, y < 0.6 (two edges
 * along x at y = 0, two along y at x = 0; the last two on a clip): the QEF puts the point on the crease line, at
 * z = 0.5 (no plane bounds z: that eigenvalue is dropped), and the nearest crossing is the first on y = 0.6. */
static int check_sheet_points(void)
{
    const long corner[1] = {0}, first[1] = {0}, strides[3] = {4, 2, 1};
    const double origin[3] = {0, 0, 0};
    const signed char plane_sheets[12] = {-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0};
    const long plane_keys[4] = {16 + 0, 16 + 2, 16 + 4, 16 + 6}; /* axis 2: (0,0,0), (0,1,0), (1,0,0), (1,1,0) */
    const double plane_points[12] = {0, 0, 0.3, 0, 1, 0.3, 1, 0, 0.3, 1, 1, 0.3};
    const double plane_normals[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    const int plane_piece[4] = {0, 0, 0, 0};
    const signed char crease_sheets[12] = {0, -1, 0, -1, 0, -1, 0, -1, -1, -1, -1, -1};
    const long crease_keys[4] = {0, 1, 8 + 0, 8 + 1}; /* axis 0 at (0,0,0), (0,0,1); axis 1 at the same */
    const double crease_points[12] = {0.4, 0, 0, 0.4, 0, 1, 0, 0.6, 0, 0, 0.6, 1};
    const double crease_normals[12] = {1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0};
    const int crease_piece[4] = {0, 0, 1, 1};
    double out[3];
    long mask[1], nearest[1];
    int failures = 0;
    ig_mesh_sheet_points(1, corner, plane_sheets, first, strides, 8, 4, plane_keys, plane_points, plane_normals,
                         plane_piece, origin, 1.0, 0.9, 0.1, 1, out, mask, nearest);
    if (!near3(out, 0.5, 0.5, 0.3) || mask[0] != 1 || nearest[0] != 0) {
        printf("plane cell: (%g, %g, %g), mask %ld, nearest %ld\n", out[0], out[1], out[2], mask[0], nearest[0]);
        ++failures;
    }
    ig_mesh_sheet_points(1, corner, crease_sheets, first, strides, 8, 4, crease_keys, crease_points, crease_normals,
                         crease_piece, origin, 1.0, 0.9, 0.1, 1, out, mask, nearest);
    if (!near3(out, 0.4, 0.6, 0.5) || mask[0] != 3 || nearest[0] != 2) {
        printf("crease cell: (%g, %g, %g), mask %ld, nearest %ld\n", out[0], out[1], out[2], mask[0], nearest[0]);
        ++failures;
    }
    mask[0] = -7; /* a sheet numbered past nverts: skipped, nothing written */
    ig_mesh_sheet_points(1, corner, crease_sheets, first, strides, 8, 4, crease_keys, crease_points, crease_normals,
                         crease_piece, origin, 1.0, 0.9, 0.1, 0, out, mask, nearest);
    if (mask[0] != -7) {
        printf("a sheet past nverts was written\n");
        ++failures;
    }
    return failures;
}

/* A quad in z = 0 whose diagonal 1-3 is the shorter, as given and flipped: the two triangles share that
 * diagonal, and face +z, then -z. */
static int check_split_quads(void)
{
    const double verts[12] = {0, 0, 0, 1, 0, 0, 1.5, 1.5, 0, 0, 1, 0};
    const long quads[8] = {0, 1, 2, 3, 0, 1, 2, 3};
    const unsigned char flip[2] = {0, 1};
    long tris[12];
    int failures = 0;
    ig_mesh_split_quads(2, quads, flip, verts, tris);
    for (int q = 0; q < 2; ++q)
        for (int t = 0; t < 2; ++t) {
            const long *tri = tris + 3 * (2 * t + q);
            const double *a = verts + 3 * tri[0], *b = verts + 3 * tri[1], *c = verts + 3 * tri[2];
            double nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            int has1 = tri[0] == 1 || tri[1] == 1 || tri[2] == 1, has3 = tri[0] == 3 || tri[1] == 3 || tri[2] == 3;
            if (!has1 || !has3 || (q == 0 ? nz <= 0 : nz >= 0)) {
                printf("quad %d, triangle %d: (%ld, %ld, %ld)\n", q, t, tri[0], tri[1], tri[2]);
                ++failures;
            }
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
    failures += check_projection(params) + check_sheet_points() + check_split_quads();
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
