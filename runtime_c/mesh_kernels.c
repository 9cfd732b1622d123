/* The mesh's C loops. See mesh_kernels.h. */
#include "mesh_kernels.h"
#include "numerics.h"

#include <math.h>
#include <stddef.h>

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

/* The crossing of each active edge of cell c (idx[e], -1 where none); returns the cell's number of sheets. */
static int cell_edges(const ig_mesh_sheets *m, long c, long at[12], long idx[12])
{
    const signed char *sh = m->sheets + 12 * (size_t)c;
    int nsheets = 0;
    for (int e = 0; e < 12; ++e) { /* edge e = 4 a + u + 2 v starts at offsets (u, v) along the other axes */
        idx[e] = -1;
        if (sh[e] < 0)
            continue;
        int a = e / 4, u = e % 2, v = (e / 2) % 2;
        int b = a == 0 ? 1 : 0, d = a == 2 ? 1 : 2;
        long key = a * m->nvertices + m->corner[c] + u * m->strides[b] + v * m->strides[d];
        idx[e] = find_key(m->keys, m->ncross, key, at + e);
        if (sh[e] + 1 > nsheets)
            nsheets = sh[e] + 1;
    }
    return nsheets;
}

/* Sheet s of a cell (its edges' sheets sh, their crossings idx): the mass point of its crossings, the unit mean
 * of their normals, and the bits of their pieces (returned). */
static long sheet_mass(const ig_mesh_sheets *m, const signed char *sh, const long idx[12], int s, double mass[3],
                       double mean[3])
{
    int count = 0;
    long bits = 0;
    for (int k = 0; k < 3; ++k)
        mass[k] = mean[k] = 0.0;
    for (int e = 0; e < 12; ++e)
        if (sh[e] == s && idx[e] >= 0) {
            const double *p = m->points + 3 * (size_t)idx[e], *n = m->normals + 3 * (size_t)idx[e];
            for (int k = 0; k < 3; ++k) {
                mass[k] += p[k];
                mean[k] += n[k];
            }
            ++count;
            if (m->piece[idx[e]] >= 0 && m->piece[idx[e]] < 63)
                bits |= 1L << m->piece[idx[e]];
        }
    double len = sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]);
    for (int k = 0; k < 3; ++k) {
        mass[k] /= count > 0 ? count : 1;
        mean[k] /= len > 1e-300 ? len : 1e-300;
    }
    return bits;
}

/* The sheet's QEF about its mass point, A^T A and A^T b of the planes through its crossings; returns whether
 * the sheet is sharp (a normal off the mean by more than acos(crease)). */
static int sheet_qef(const ig_mesh_sheets *m, const signed char *sh, const long idx[12], int s, const double mass[3],
                     const double mean[3], double ata[3][3], double atb[3])
{
    int sharp = 0;
    for (int i = 0; i < 3; ++i) {
        atb[i] = 0.0;
        for (int j = 0; j < 3; ++j)
            ata[i][j] = 0.0;
    }
    for (int e = 0; e < 12; ++e)
        if (sh[e] == s && idx[e] >= 0) {
            const double *p = m->points + 3 * (size_t)idx[e], *n = m->normals + 3 * (size_t)idx[e];
            if (n[0] * mean[0] + n[1] * mean[1] + n[2] * mean[2] < m->crease)
                sharp = 1;
            double nq = n[0] * (p[0] - mass[0]) + n[1] * (p[1] - mass[1]) + n[2] * (p[2] - mass[2]);
            for (int i = 0; i < 3; ++i) {
                atb[i] += n[i] * nq;
                for (int j = 0; j < 3; ++j)
                    ata[i][j] += n[i] * n[j];
            }
        }
    return sharp;
}

/* o += the QEF's minimiser about the mass point, eigenvalues below drop x the largest (or not positive) dropped;
 * ata is overwritten. */
static void qef_shift(double ata[3][3], const double atb[3], double drop, double o[3])
{
    double w[3], v[3][3], top;
    ig_sym3_eigen(ata, w, v);
    top = fmax(w[0], fmax(w[1], w[2]));
    for (int j = 0; j < 3; ++j) {
        if (!(w[j] > drop * top) || !(w[j] > 0))
            continue;
        double y = (v[0][j] * atb[0] + v[1][j] * atb[1] + v[2][j] * atb[2]) / w[j];
        for (int k = 0; k < 3; ++k)
            o[k] += v[k][j] * y;
    }
}

/* The index of the sheet's crossing nearest o (-1: none). */
static long nearest_crossing(const ig_mesh_sheets *m, const signed char *sh, const long idx[12], int s,
                             const double o[3])
{
    long best = -1;
    double best_d = INFINITY;
    for (int e = 0; e < 12; ++e)
        if (sh[e] == s && idx[e] >= 0) {
            const double *p = m->points + 3 * (size_t)idx[e];
            double dd = (p[0] - o[0]) * (p[0] - o[0]) + (p[1] - o[1]) * (p[1] - o[1]) + (p[2] - o[2]) * (p[2] - o[2]);
            if (dd < best_d) {
                best_d = dd;
                best = idx[e];
            }
        }
    return best;
}

/* Vertex vid: sheet s of cell c, whose lower corner is grid cell `cell`. */
static void sheet_vertex(const ig_mesh_sheets *m, long c, const long idx[12], int s, const long cell[3], long vid)
{
    const signed char *sh = m->sheets + 12 * (size_t)c;
    double mass[3], mean[3], ata[3][3], atb[3], *o = m->out + 3 * (size_t)vid;
    long bits = sheet_mass(m, sh, idx, s, mass, mean);
    int sharp = sheet_qef(m, sh, idx, s, mass, mean, ata, atb);
    for (int k = 0; k < 3; ++k)
        o[k] = mass[k];
    if (sharp)
        qef_shift(ata, atb, m->drop, o);
    for (int k = 0; k < 3; ++k) { /* clamped to the cell */
        double lo = m->origin[k] + m->h * (double)cell[k];
        o[k] = o[k] < lo ? lo : o[k]; /* as NumPy's clip: a NaN stays NaN */
        o[k] = o[k] > lo + m->h ? lo + m->h : o[k];
    }
    m->mask[vid] = bits;
    m->nearest[vid] = nearest_crossing(m, sh, idx, s, o);
}

void ig_mesh_sheet_points(const ig_mesh_sheets *m)
{
    if (!m || !m->corner || !m->sheets || !m->first || !m->strides || !m->keys || !m->points || !m->normals ||
        !m->piece || !m->origin || !m->out || !m->mask || !m->nearest)
        return;
    long at[12] = {0};
    for (long c = 0; c < m->ncells; ++c) {
        long idx[12], corner = m->corner[c];
        long cell[3] = {corner / m->strides[0], corner % m->strides[0] / m->strides[1], corner % m->strides[1]};
        int nsheets = cell_edges(m, c, at, idx);
        for (int s = 0; s < nsheets; ++s) {
            long vid = m->first[c] + s;
            if (vid >= 0 && vid < m->nverts) /* else the caller's numbering disagrees: nothing written */
                sheet_vertex(m, c, idx, s, cell, vid);
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
