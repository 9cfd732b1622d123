/* Batch forms of ig_shape_roots and of the shape's value and gradient. See shape_batch.h. */
#include "shape_batch.h"
#include <math.h>

#include <stddef.h>

void ig_shape_roots_many(const ig_shape *shape, const double *params, long n, const double *o, const double *d,
                         const double *tmin, const double *tmax, ig_root_method method, double *roots, int *counts)
{
    ig_shape_prep prep;
    if (!shape || !o || !d || !tmin || !tmax || !roots || !counts)
        return;
    ig_shape_prepare(shape, params, &prep);
    for (long i = 0; i < n; ++i) {
        double *r = roots + (size_t)i * IG_MAX_DEGREE;
        counts[i] = shape->coeffs ? ig_shape_solve(shape, params, &prep, o + 3 * (size_t)i, d + 3 * (size_t)i, tmin[i],
                                                   tmax[i], method, 0, r, NULL)
                                  : 0;
    }
}

void ig_shape_eval_many(const ig_shape *shape, const double *params, long n, const double *p, double *f, double *g)
{
    if (!shape || !p || !f)
        return;
    for (long i = 0; i < n; ++i) { /* a shape without value or gradient gives NaN, never leaves them unwritten */
        f[i] = shape->value ? shape->value(p + 3 * (size_t)i, params) : NAN;
        if (g && shape->gradient)
            shape->gradient(p + 3 * (size_t)i, params, g + 3 * (size_t)i);
        else if (g)
            g[3 * (size_t)i] = g[3 * (size_t)i + 1] = g[3 * (size_t)i + 2] = NAN;
    }
}

void ig_shape_values_grid(const ig_shape *shape, const double *params, const double *x, long nx, const double *y,
                          long ny, const double *z, long nz, double *f)
{
    if (!shape || !shape->value || !x || !y || !z || !f)
        return;
    for (long i = 0; i < nx; ++i)
        for (long j = 0; j < ny; ++j)
            for (long k = 0; k < nz; ++k) {
                double p[3] = {x[i], y[j], z[k]};
                f[((size_t)i * (size_t)ny + (size_t)j) * (size_t)nz + (size_t)k] = shape->value(p, params);
            }
}

/* One point's Newton steps of least norm onto f = 0; 1 when it converged (see shape_batch.h). */
static int project_one(const ig_shape *shape, const double *params, double *p, int steps, double tol, double noise)
{
    double prev = INFINITY, size = INFINITY;
    for (int k = 0; k < steps; ++k) {
        double g[3], s[3];
        double f = shape->value(p, params);
        shape->gradient(p, params, g);
        double gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
        if (!(gg > 0)) /* no direction to step in */
            return 0;
        double c = -(f / gg);
        for (int i = 0; i < 3; ++i)
            s[i] = c * g[i];
        if (!isfinite(s[0]) || !isfinite(s[1]) || !isfinite(s[2]))
            return 0;
        for (int i = 0; i < 3; ++i)
            p[i] += s[i];
        size = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        if (size <= tol || (size > 0.5 * prev && size <= noise))
            return 1;
        prev = size;
    }
    return size <= noise;
}

void ig_shape_project_many(const ig_shape *shape, const double *params, long n, double *p, int steps, double tol,
                           double noise, double reach, unsigned char *ok)
{
    if (!shape || !p || !ok)
        return;
    for (long i = 0; i < n; ++i) {
        double *q = p + 3 * (size_t)i, start[3] = {q[0], q[1], q[2]};
        int done = shape->value && shape->gradient && project_one(shape, params, q, steps, tol, noise);
        for (int k = 0; k < 3; ++k) /* NaN fails this test too */
            done = done && fabs(q[k] - start[k]) <= reach;
        ok[i] = (unsigned char)done;
    }
}

/* The eigenvalues w and unit eigenvectors (columns of v) of the symmetric 3x3 matrix a, by cyclic Jacobi
 * rotations; a is overwritten. */
static void sym3_eigen(double a[3][3], double w[3], double v[3][3])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            v[i][j] = i == j;
    for (int sweep = 0; sweep < 50; ++sweep) {
        double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (!(off > 1e-34 * diag))
            break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (a[p][q] == 0.0)
                    continue;
                double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                if (!isfinite(t)) /* theta's square overflowed: t ~ 1 / (2 theta) */
                    t = 0.5 / theta;
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                double r[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, m[3][3];
                r[p][p] = r[q][q] = c;
                r[p][q] = s;
                r[q][p] = -s;
                for (int i = 0; i < 3; ++i) /* m = a r */
                    for (int j = 0; j < 3; ++j)
                        m[i][j] = a[i][0] * r[0][j] + a[i][1] * r[1][j] + a[i][2] * r[2][j];
                for (int i = 0; i < 3; ++i) /* a = r^T m */
                    for (int j = 0; j < 3; ++j)
                        a[i][j] = r[0][i] * m[0][j] + r[1][i] * m[1][j] + r[2][i] * m[2][j];
                a[p][q] = a[q][p] = 0.0;
                for (int i = 0; i < 3; ++i) { /* v = v r */
                    double vp = v[i][p], vq = v[i][q];
                    v[i][p] = c * vp - s * vq;
                    v[i][q] = s * vp + c * vq;
                }
            }
    }
    for (int i = 0; i < 3; ++i)
        w[i] = a[i][i];
}

/* The index of edge key `key` in the ascending keys[0 .. n), or -1. *at: where the last search for this edge of
 * the cell ended; the cells come in ascending order, so the next key is usually a few entries further on. */
static long find_key(const long *keys, long n, long key, long *at)
{
    long lo = 0, hi = n;
    if (*at < n && keys[*at] <= key) { /* a few steps forward, then a binary search in what is left */
        lo = *at;
        for (int k = 0; k < 8 && lo < n && keys[lo] < key; ++k)
            ++lo;
    }
    while (lo < hi) {
        long mid = lo + (hi - lo) / 2;
        if (keys[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    *at = lo;
    return lo < n && keys[lo] == key ? lo : -1;
}

void ig_mesh_sheet_points(long ncells, const long *corner, const signed char *sheets, const long *first,
                          const long *strides, long nvertices, long ncross, const long *keys, const double *points,
                          const double *normals, const int *piece, const double *origin, double h, double crease,
                          double drop, long nverts, double *out, long *mask, long *nearest)
{
    if (!corner || !sheets || !first || !strides || !keys || !points || !normals || !piece || !origin || !out ||
        !mask || !nearest)
        return;
    long at[12] = {0};
    for (long c = 0; c < ncells; ++c) {
        const signed char *sh = sheets + 12 * (size_t)c;
        long idx[12];
        int nsheets = 0;
        long cell[3] = {corner[c] / strides[0], corner[c] % strides[0] / strides[1], corner[c] % strides[1]};
        for (int e = 0; e < 12; ++e) { /* edge e = 4 a + u + 2 v starts at offsets (u, v) along the other axes */
            idx[e] = -1;
            if (sh[e] < 0)
                continue;
            int a = e / 4, u = e % 2, v = (e / 2) % 2;
            int b = a == 0 ? 1 : 0, d = a == 2 ? 1 : 2;
            idx[e] = find_key(keys, ncross, a * nvertices + corner[c] + u * strides[b] + v * strides[d], at + e);
            if (sh[e] + 1 > nsheets)
                nsheets = sh[e] + 1;
        }
        for (int s = 0; s < nsheets; ++s) {
            long vid = first[c] + s;
            if (vid < 0 || vid >= nverts) /* the caller's numbering disagrees: nothing written out of bounds */
                continue;
            double mass[3] = {0, 0, 0}, mean[3] = {0, 0, 0};
            int count = 0, sharp = 0;
            long m = 0;
            for (int e = 0; e < 12; ++e)
                if (sh[e] == s && idx[e] >= 0) {
                    const double *p = points + 3 * (size_t)idx[e], *n = normals + 3 * (size_t)idx[e];
                    for (int k = 0; k < 3; ++k) {
                        mass[k] += p[k];
                        mean[k] += n[k];
                    }
                    ++count;
                    if (piece[idx[e]] >= 0 && piece[idx[e]] < 63)
                        m |= 1L << piece[idx[e]];
                }
            double len = sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]);
            for (int k = 0; k < 3; ++k) {
                mass[k] /= count > 0 ? count : 1;
                mean[k] /= len > 1e-300 ? len : 1e-300;
            }
            double ata[3][3] = {{0}}, atb[3] = {0, 0, 0};
            for (int e = 0; e < 12; ++e)
                if (sh[e] == s && idx[e] >= 0) {
                    const double *p = points + 3 * (size_t)idx[e], *n = normals + 3 * (size_t)idx[e];
                    if (n[0] * mean[0] + n[1] * mean[1] + n[2] * mean[2] < crease)
                        sharp = 1;
                    double nq = n[0] * (p[0] - mass[0]) + n[1] * (p[1] - mass[1]) + n[2] * (p[2] - mass[2]);
                    for (int i = 0; i < 3; ++i) {
                        atb[i] += n[i] * nq;
                        for (int j = 0; j < 3; ++j)
                            ata[i][j] += n[i] * n[j];
                    }
                }
            double *o = out + 3 * (size_t)vid;
            for (int k = 0; k < 3; ++k)
                o[k] = mass[k];
            if (sharp) { /* the QEF's minimiser about the mass point, small eigenvalues dropped */
                double w[3], v[3][3], top;
                sym3_eigen(ata, w, v);
                top = fmax(w[0], fmax(w[1], w[2]));
                for (int j = 0; j < 3; ++j) {
                    if (!(w[j] > drop * top) || !(w[j] > 0))
                        continue;
                    double y = (v[0][j] * atb[0] + v[1][j] * atb[1] + v[2][j] * atb[2]) / w[j];
                    for (int k = 0; k < 3; ++k)
                        o[k] += v[k][j] * y;
                }
            }
            long best = -1;
            double best_d = INFINITY;
            for (int k = 0; k < 3; ++k) { /* clamped to the cell */
                double lo = origin[k] + h * (double)cell[k];
                o[k] = o[k] < lo ? lo : o[k]; /* as NumPy's clip: a NaN stays NaN */
                o[k] = o[k] > lo + h ? lo + h : o[k];
            }
            for (int e = 0; e < 12; ++e)
                if (sh[e] == s && idx[e] >= 0) {
                    const double *p = points + 3 * (size_t)idx[e];
                    double dd =
                        (p[0] - o[0]) * (p[0] - o[0]) + (p[1] - o[1]) * (p[1] - o[1]) + (p[2] - o[2]) * (p[2] - o[2]);
                    if (dd < best_d) {
                        best_d = dd;
                        best = idx[e];
                    }
                }
            mask[vid] = m;
            nearest[vid] = best;
        }
    }
}

static double dist2(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

void ig_mesh_split_quads(long m, const long *quads, const unsigned char *flip, const double *verts, long *tris)
{
    static const int keep[2][2][3] = {{{0, 1, 2}, {0, 2, 3}}, {{1, 2, 3}, {1, 3, 0}}};
    if (!quads || !flip || !verts || !tris)
        return;
    for (long i = 0; i < m; ++i) {
        long q[4];
        for (int k = 0; k < 4; ++k)
            q[k] = quads[4 * (size_t)i + (size_t)(flip[i] ? 3 - k : k)];
        int alt = dist2(verts + 3 * (size_t)q[1], verts + 3 * (size_t)q[3]) <
                  dist2(verts + 3 * (size_t)q[0], verts + 3 * (size_t)q[2]);
        for (int t = 0; t < 2; ++t)
            for (int k = 0; k < 3; ++k)
                tris[3 * ((size_t)t * (size_t)m + (size_t)i) + (size_t)k] = q[keep[alt][t][k]];
    }
}
