/* runtime_c/mesh_kernels.c, case by case (tests/c/ctest.h; tests/test_mesh_kernels_c.py runs them under ASan +
 * UBSan): one cell cut by a plane and by a crease, whose dual points are known; a sheet numbered past the
 * caller's vertices; a quad whose shorter diagonal is known. */
#include <math.h>
#include <string.h>

#include "ctest.h"
#include "mesh_kernels.h"

static int near3(const double *p, double x, double y, double z)
{
    return fabs(p[0] - x) < 1e-12 && fabs(p[1] - y) < 1e-12 && fabs(p[2] - z) < 1e-12;
}

/* The unit cell [0, 1]^3 of a grid of 2 x 2 x 2 vertices (strides 4, 2, 1), one sheet, vertex 0. */
static const long CORNER[1] = {0}, FIRST[1] = {0}, STRIDES[3] = {4, 2, 1};
static const double ORIGIN[3] = {0, 0, 0};

static ig_mesh_sheets unit_cell(const signed char *sheets, const long *keys, const double *points,
                                const double *normals, const int *piece, double *out, long *mask, long *nearest)
{
    ig_mesh_sheets m;
    memset(&m, 0, sizeof m);
    m.ncells = 1;
    m.corner = CORNER;
    m.sheets = sheets;
    m.first = FIRST;
    m.strides = STRIDES;
    m.nvertices = 8;
    m.origin = ORIGIN;
    m.h = 1.0;
    m.ncross = 4;
    m.keys = keys;
    m.points = points;
    m.normals = normals;
    m.piece = piece;
    m.crease = 0.9;
    m.drop = 0.1;
    m.nverts = 1;
    m.out = out;
    m.mask = mask;
    m.nearest = nearest;
    return m;
}

/* Cut by the plane z = 0.3: four edges along z, one sheet, its point the crossings' mass point. */
static void plane_cell_gives_the_mass_point(ctest *t)
{
    const signed char sheets[12] = {-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0};
    const long keys[4] = {16 + 0, 16 + 2, 16 + 4, 16 + 6}; /* axis 2: (0,0,0), (0,1,0), (1,0,0), (1,1,0) */
    const double points[12] = {0, 0, 0.3, 0, 1, 0.3, 1, 0, 0.3, 1, 1, 0.3};
    const double normals[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    const int piece[4] = {0, 0, 0, 0};
    double out[3];
    long mask[1], nearest[1];
    ig_mesh_sheets m = unit_cell(sheets, keys, points, normals, piece, out, mask, nearest);
    ig_mesh_sheet_points(&m);
    CHECK(t, near3(out, 0.5, 0.5, 0.3) && mask[0] == 1 && nearest[0] == 0);
}

/* The crease x < 0.4, y < 0.6 (two edges along x at y = 0, two along y at x = 0; the last two on a clip): the
 * QEF puts the point on the crease line, at z = 0.5 (no plane bounds z: that eigenvalue is dropped), and the
 * nearest crossing is the first on y = 0.6. */
static const signed char CREASE_SHEETS[12] = {0, -1, 0, -1, 0, -1, 0, -1, -1, -1, -1, -1};
static const long CREASE_KEYS[4] = {0, 1, 8 + 0, 8 + 1}; /* axis 0 at (0,0,0), (0,0,1); axis 1 at the same */
static const double CREASE_POINTS[12] = {0.4, 0, 0, 0.4, 0, 1, 0, 0.6, 0, 0, 0.6, 1};
static const double CREASE_NORMALS[12] = {1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0};
static const int CREASE_PIECE[4] = {0, 0, 1, 1};

static void crease_cell_puts_the_point_on_the_crease(ctest *t)
{
    double out[3];
    long mask[1], nearest[1];
    ig_mesh_sheets m =
        unit_cell(CREASE_SHEETS, CREASE_KEYS, CREASE_POINTS, CREASE_NORMALS, CREASE_PIECE, out, mask, nearest);
    ig_mesh_sheet_points(&m);
    CHECK(t, near3(out, 0.4, 0.6, 0.5) && mask[0] == 3 && nearest[0] == 2);
}

/* The hard case: a sheet numbered past the caller's vertices, and a NULL array: nothing is written. */
static void a_sheet_past_the_vertices_is_skipped(ctest *t)
{
    double out[3] = {-7, -7, -7};
    long mask[1] = {-7}, nearest[1] = {-7};
    ig_mesh_sheets m =
        unit_cell(CREASE_SHEETS, CREASE_KEYS, CREASE_POINTS, CREASE_NORMALS, CREASE_PIECE, out, mask, nearest);
    m.nverts = 0;
    ig_mesh_sheet_points(&m);
    CHECK(t, mask[0] == -7 && nearest[0] == -7 && out[0] == -7);
    m.nverts = 1;
    m.keys = NULL;
    ig_mesh_sheet_points(&m);
    CHECK(t, mask[0] == -7 && out[0] == -7);
    ig_mesh_sheet_points(NULL);
}

/* A quad in z = 0 whose diagonal 1-3 is the shorter, as given and flipped: the two triangles share that
 * diagonal, and face +z, then -z. */
static void split_quads_takes_the_shorter_diagonal(ctest *t)
{
    const double verts[12] = {0, 0, 0, 1, 0, 0, 1.5, 1.5, 0, 0, 1, 0};
    const long quads[8] = {0, 1, 2, 3, 0, 1, 2, 3};
    const unsigned char flip[2] = {0, 1};
    long tris[12];
    ig_mesh_split_quads(2, quads, flip, verts, tris);
    for (int q = 0; q < 2; ++q)
        for (int k = 0; k < 2; ++k) {
            const long *tri = tris + 3 * (2 * k + q);
            const double *a = verts + 3 * tri[0], *b = verts + 3 * tri[1], *c = verts + 3 * tri[2];
            double nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            int has1 = tri[0] == 1 || tri[1] == 1 || tri[2] == 1, has3 = tri[0] == 3 || tri[1] == 3 || tri[2] == 3;
            CHECK(t, has1 && has3 && (q == 0 ? nz > 0 : nz < 0));
        }
}

static const ctest_case CASES[] = {
    CTEST_CASE(plane_cell_gives_the_mass_point),
    CTEST_CASE(crease_cell_puts_the_point_on_the_crease),
    CTEST_CASE(a_sheet_past_the_vertices_is_skipped),
    CTEST_CASE(split_quads_takes_the_shorter_diagonal),
};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
