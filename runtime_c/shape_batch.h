/* Many rays, or many points, of one shape in one call: what `implgen mesh` asks of a shape (every grid line is
 * a ray; every crossing point needs f and its gradient). One call costs n solves in C, not n calls from Python.
 * Pointers must not be NULL (params may be NULL when the shape has none); arrays hold n entries each
 * (3 n for points and directions, n * IG_MAX_DEGREE for roots). No state is kept between calls. */
#ifndef IMPLGEN_SHAPE_BATCH_H
#define IMPLGEN_SHAPE_BATCH_H

#include "shape.h"

/* For each ray i: every distinct root of f(o_i + t d_i) in [tmin_i, tmax_i], ascending, what ig_shape_roots
 * gives bit for bit, into roots[i * IG_MAX_DEGREE ...], and their count into counts[i]. */
void ig_shape_roots_many(const ig_shape *shape, const double *params, long n, const double *o, const double *d,
                         const double *tmin, const double *tmax, ig_root_method method, double *roots, int *counts);

/* For each point i: f(p_i) into f[i] and grad f(p_i) into g[3 i ...] (g may be NULL: values only); NaN where
 * the shape has no value or gradient function. */
void ig_shape_eval_many(const ig_shape *shape, const double *params, long n, const double *p, double *f, double *g);

/* f at every point (x[i], y[j], z[k]) of a grid into f[(i * ny + j) * nz + k] (C order): a grid's values
 * without an array of its points. */
void ig_shape_values_grid(const ig_shape *shape, const double *params, const double *x, long nx, const double *y,
                          long ny, const double *z, long nz, double *f);

/* Each point p_i moved onto f = 0 by Newton steps of least norm, p += -f grad f / |grad f|^2, at most `steps` of
 * them, in place. ok[i] = 1 when it converged -- a step of at most `tol`, or a step at most `noise` that did not
 * halve the one before (f's rounding), or a last step at most `noise` -- and moved at most `reach` along each
 * axis; 0 otherwise, and when a step is not finite (the point is left where that step would have started). */
void ig_shape_project_many(const ig_shape *shape, const double *params, long n, double *p, int steps, double tol,
                           double noise, double reach, unsigned char *ok);

/* The dual vertex of every sheet of every active cell of a grid (implgen mesh, dual.py). Cell c has its lower
 * corner at grid vertex corner[c] (flat, C order, strides[3] the grid's vertex strides, nvertices vertices),
 * sheets[12 c + e] the sheet of its edge e (-1: not active; numbering of cells.py) and its sheets' vertices
 * numbered from first[c]. Crossings: keys[ncross] ascending, axis * nvertices + the edge's lower vertex, with
 * points, unit normals (3 each) and piece (0: f, j: clip j). Per vertex: out[3 v ...] the mass point of its
 * crossings, or where a normal lies off their mean by more than acos(crease) the QEF minimiser about it (small
 * eigenvalues, below drop x the largest, dropped), clamped to the cell [origin + h idx, + h]; mask[v] the bits
 * of its crossings' pieces; nearest[v] the index of its crossing nearest out (-1: none); v < nverts, the
 * length of mask and nearest (a sheet numbered past it is skipped). */
void ig_mesh_sheet_points(long ncells, const long *corner, const signed char *sheets, const long *first,
                          const long *strides, long nvertices, long ncross, const long *keys, const double *points,
                          const double *normals, const int *piece, const double *origin, double h, double crease,
                          double drop, long nverts, double *out, long *mask, long *nearest);

/* Quads (m x 4 vertex ids, counter-clockwise about their edge's axis; flip[i]: reversed) into triangles on the
 * shorter diagonal: tris[3 i ...] the first of quad i, tris[3 (m + i) ...] the second. */
void ig_mesh_split_quads(long m, const long *quads, const unsigned char *flip, const double *verts, long *tris);

#endif
