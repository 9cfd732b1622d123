/* The mesh's C loops (implgen mesh, generator/implgen/mesh/): the dual vertex of every sheet of every active
 * cell, and quads into triangles. Plain arrays in, plain arrays out; no shape is evaluated here and no state is
 * kept between calls. */
#ifndef IMPLGEN_MESH_KERNELS_H
#define IMPLGEN_MESH_KERNELS_H

/* What ig_mesh_sheet_points reads and writes (mesh/shapelib.py fills it). Cell c has its lower corner at grid
 * vertex corner[c] (flat, C order, strides[3] the grid's vertex strides, nvertices vertices, the grid's
 * vertex 0 at origin, spacing h), sheets[12 c + e] the sheet of its edge e (-1: not active; numbering of
 * cells.py) and its sheets' vertices numbered from first[c]. Crossings: keys[ncross] ascending, axis *
 * nvertices + the edge's lower vertex, with points, unit normals (3 each) and piece (0: f, j: clip j). */
typedef struct ig_mesh_sheets {
    long ncells;
    const long *corner;
    const signed char *sheets;
    const long *first;
    const long *strides;
    long nvertices;
    const double *origin;
    double h;
    long ncross;
    const long *keys;
    const double *points, *normals;
    const int *piece;
    double crease, drop; /* a sheet is sharp where a normal lies off the mean by more than acos(crease) */
    long nverts;         /* the length of out (x 3), mask and nearest */
    double *out;
    long *mask, *nearest;
} ig_mesh_sheets;

/* Per vertex v < nverts (a sheet numbered past it is skipped): out[3 v ...] the mass point of its crossings, or
 * where its sheet is sharp the QEF minimiser about it (small eigenvalues, below drop x the largest, dropped),
 * clamped to the cell [origin + h idx, + h]; mask[v] the bits of its crossings' pieces; nearest[v] the index of
 * its crossing nearest out (-1: none). Nothing is done when a pointer is NULL. */
void ig_mesh_sheet_points(const ig_mesh_sheets *m);

/* Quads (m x 4 vertex ids, counter-clockwise about their edge's axis; flip[i]: reversed) into triangles on the
 * shorter diagonal: tris[3 i ...] the first of quad i, tris[3 (m + i) ...] the second. */
void ig_mesh_split_quads(long m, const long *quads, const unsigned char *flip, const double *verts, long *tris);

#endif
