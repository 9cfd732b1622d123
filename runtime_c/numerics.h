/* Small numerical kernels shared by the solvers, the shape layer and the tracer, defined once here as
 * static inline functions (they sit in hot loops; every caller gets its own inlined copy of the same
 * arithmetic).
 *
 * - error-free transformations: a + b and a * b as an unevaluated sum of two doubles, exactly;
 * - Horner's rule, plain and compensated (as accurate as Horner in twice the working precision);
 * - one axis of the slab test of a ray against an axis-aligned box;
 * - a vector's length and unit direction;
 * - affine 3x4 maps (row-major, as tracer.h): a point, a vector, the inverse, a ray's unit object-space
 *   direction, a normal, a box (the tracer and the Embree adapter move rays into object space, normals and
 *   boxes into world space with these, so both see the same numbers to the last bit);
 * - the eigen-decomposition of a symmetric 3x3 matrix (the mesh's dual-contouring vertex).
 *
 * Each has a named test in tests/c/test_numerics.c, its hard case among them.
 */
#ifndef IMPLGEN_NUMERICS_H
#define IMPLGEN_NUMERICS_H

#include <float.h>
#include <math.h>

/* s + e == a + b exactly, s = fl(a + b) (Knuth's TwoSum: no condition on the magnitudes). */
static inline void ig_two_sum(double a, double b, double *s, double *e)
{
    double x = a + b;
    double z = x - a;
    *e = (a - (x - z)) + (b - z);
    *s = x;
}

/* p + e == a * b exactly, p = fl(a * b): Dekker's product without FMA (the library is built for baseline
 * x86-64, where fma() is a slow call). Exact unless a * b underflows or a, b are beyond 2^996. */
static inline void ig_two_prod(double a, double b, double *p, double *e)
{
    const double split = 134217729.0; /* 2^27 + 1 */
    double x = a * b;
    double fa = split * a, fb = split * b;
    double ah = fa - (fa - a), al = a - ah;
    double bh = fb - (fb - b), bl = b - bh;
    *e = al * bl - (((x - ah * bh) - al * bh) - ah * bl);
    *p = x;
}

/* The larger of a and b, ignoring a NaN in b (fmax is a library call unless math errors are off). */
static inline double ig_max(double a, double b) { return b > a ? b : a; }

/* c[0] + c[1] x + ... + c[n] x^n by Horner's rule. */
static inline double ig_horner(const double *c, int n, double x)
{
    double v = c[n];
    for (int k = n - 1; k >= 0; --k)
        v = v * x + c[k];
    return v;
}

/* sum |c_k| x^k for x >= 0, by Horner's rule on the absolute values: the scale against which the rounding
 * error of evaluating the polynomial at +-x is bounded. */
static inline double ig_horner_abs(const double *c, int n, double x)
{
    double v = fabs(c[n]);
    for (int k = n - 1; k >= 0; --k)
        v = v * x + fabs(c[k]);
    return v;
}

/* The same by compensated Horner (Graillat, Langlois, Louvet 2005): the rounding error of every step is
 * carried along exactly and added back at the end, so the result is as accurate as Horner's rule in twice
 * the working precision. */
static inline double ig_horner_compensated(const double *c, int n, double x)
{
    double r = c[n], err = 0.0;
    for (int k = n - 1; k >= 0; --k) {
        double pr, pe, se;
        ig_two_prod(r, x, &pr, &pe);
        ig_two_sum(pr, c[k], &r, &se);
        err = err * x + (pe + se);
    }
    return r + err;
}

/* One axis of the slab test: the ray coordinate o + t d (d != 0, inv = 1 / d) lies between the planes lo and
 * hi for t in [*ta, *tb] (ordered). Returns 1 when ordering swapped the two (d < 0: the ray enters through
 * hi), else 0. A NaN plane gives a NaN end and no swap. Every ray/box clip of the runtime (shape.c,
 * tracer_hit.c) is built on this, so they all compute the same distances to the last bit. */
static inline int ig_slab(double lo, double hi, double o, double inv, double *ta, double *tb)
{
    double a = (lo - o) * inv, b = (hi - o) * inv;
    if (a > b) {
        *ta = b;
        *tb = a;
        return 1;
    }
    *ta = a;
    *tb = b;
    return 0;
}

/* out = M p + translation (out may alias p). */
static inline void ig_affine_point(const double m[12], const double p[3], double out[3])
{
    double r[3];
    int i;
    for (i = 0; i < 3; ++i)
        r[i] = m[4 * i] * p[0] + m[4 * i + 1] * p[1] + m[4 * i + 2] * p[2] + m[4 * i + 3];
    out[0] = r[0];
    out[1] = r[1];
    out[2] = r[2];
}

/* out = M v, the linear part only (out may alias v). */
static inline void ig_affine_vector(const double m[12], const double v[3], double out[3])
{
    double r[3];
    int i;
    for (i = 0; i < 3; ++i)
        r[i] = m[4 * i] * v[0] + m[4 * i + 1] * v[1] + m[4 * i + 2] * v[2];
    out[0] = r[0];
    out[1] = r[1];
    out[2] = r[2];
}

/* inv = M^-1 by cofactors. Returns 0 (inv untouched) when M's linear part is zero, not finite, or singular to
 * within 1e-12 of its scale cubed. */
static inline int ig_affine_invert(const double m[12], double inv[12])
{
    double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], k = m[10];
    double c00 = e * k - f * h, c01 = c * h - b * k, c02 = b * f - c * e;
    double c10 = f * g - d * k, c11 = a * k - c * g, c12 = c * d - a * f;
    double c20 = d * h - e * g, c21 = b * g - a * h, c22 = a * e - b * d;
    double det = a * c00 + b * c10 + c * c20;
    double scale = 0.0, t[3];
    int i;
    for (i = 0; i < 12; ++i)
        if (i % 4 != 3 && fabs(m[i]) > scale)
            scale = fabs(m[i]);
    if (!(scale > 0.0) || !isfinite(det) || fabs(det) <= 1e-12 * scale * scale * scale)
        return 0;
    inv[0] = c00 / det;
    inv[1] = c01 / det;
    inv[2] = c02 / det;
    inv[4] = c10 / det;
    inv[5] = c11 / det;
    inv[6] = c12 / det;
    inv[8] = c20 / det;
    inv[9] = c21 / det;
    inv[10] = c22 / det;
    inv[3] = inv[7] = inv[11] = 0.0;
    t[0] = m[3];
    t[1] = m[7];
    t[2] = m[11];
    ig_affine_vector(inv, t, t);
    inv[3] = -t[0];
    inv[7] = -t[1];
    inv[11] = -t[2];
    return 1;
}

/* The length L of v and, when L is positive and finite (the caller checks), the unit vector u = v / L. */
static inline double ig_unit_vector(const double v[3], double u[3])
{
    double L = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    int i;
    if (L > 0.0 && isfinite(L))
        for (i = 0; i < 3; ++i)
            u[i] = v[i] / L;
    return L;
}

/* The ray o + t d in the object space of the map whose inverse is minv (NULL: the identity), as the solves take
 * it: the origin oo and the unit direction u. Returns the length L of the object-space direction (the solve's
 * parameter is s = t L); u is set only when L is positive and finite, which the caller checks. */
static inline double ig_affine_unit_ray(const double *minv, const double o[3], const double d[3], double oo[3],
                                        double u[3])
{
    double od[3];
    int i;
    if (minv) {
        ig_affine_point(minv, o, oo);
        ig_affine_vector(minv, d, od);
    } else {
        for (i = 0; i < 3; ++i) {
            oo[i] = o[i];
            od[i] = d[i];
        }
    }
    return ig_unit_vector(od, u);
}

/* The unit world normal n = minv^T g / |minv^T g| of the object-space normal g (normals map by the inverse
 * transpose). Returns 0 (n unnormalised) when that has no length or is not finite. */
static inline int ig_affine_normal(const double minv[12], const double g[3], double n[3])
{
    double len;
    int i;
    for (i = 0; i < 3; ++i)
        n[i] = minv[i] * g[0] + minv[4 + i] * g[1] + minv[8 + i] * g[2];
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0.0) || !isfinite(len))
        return 0;
    for (i = 0; i < 3; ++i)
        n[i] /= len;
    return 1;
}

/* The box {xmin, ymin, zmin, xmax, ymax, zmax} around the image of the object box ob under m, padded outward by
 * 1e-9 of its finite size (the rounding of the images is ~1e-16 relative: the padded box holds them with
 * room). A finite box: its 8 corners through m. Sides of ob may be infinite (an axis the spec leaves open):
 * then each world axis sums the entries' extremes, an entry of m that is 0 adding nothing, so a world axis that
 * no open object axis reaches stays finite. Returns 1 when all six sides of the result are finite. */
static inline int ig_affine_box(const double m[12], const double ob[6], double wb[6])
{
    double ext = 0.0, mag = 0.0, pad;
    int a, i, finite = 1;
    for (a = 0; a < 6; ++a)
        finite = finite && isfinite(ob[a]);
    for (a = 0; a < 3; ++a) {
        wb[a] = finite ? INFINITY : m[4 * a + 3];
        wb[a + 3] = finite ? -INFINITY : m[4 * a + 3];
    }
    if (finite) {
        for (i = 0; i < 8; ++i) {
            double c[3], w[3];
            c[0] = ob[(i & 1) ? 3 : 0];
            c[1] = ob[(i & 2) ? 4 : 1];
            c[2] = ob[(i & 4) ? 5 : 2];
            ig_affine_point(m, c, w);
            for (a = 0; a < 3; ++a) {
                if (w[a] < wb[a])
                    wb[a] = w[a];
                if (w[a] > wb[a + 3])
                    wb[a + 3] = w[a];
            }
        }
    } else {
        for (a = 0; a < 3; ++a)
            for (i = 0; i < 3; ++i) {
                double e = m[4 * a + i], lo, hi;
                if (e == 0.0)
                    continue;
                lo = e * ob[i];
                hi = e * ob[i + 3];
                wb[a] += lo < hi ? lo : hi;
                wb[a + 3] += lo < hi ? hi : lo;
            }
    }
    for (a = 0; a < 3; ++a) {
        if (isfinite(wb[a + 3] - wb[a]) && wb[a + 3] - wb[a] > ext)
            ext = wb[a + 3] - wb[a];
        if (isfinite(wb[a]) && fabs(wb[a]) > mag)
            mag = fabs(wb[a]);
        if (isfinite(wb[a + 3]) && fabs(wb[a + 3]) > mag)
            mag = fabs(wb[a + 3]);
    }
    pad = 1e-9 * (ext + mag) + DBL_MIN;
    for (a = 0; a < 3; ++a) {
        wb[a] = isnan(wb[a]) ? -INFINITY : wb[a] - pad; /* NaN (inf - inf): open, never an empty box */
        wb[a + 3] = isnan(wb[a + 3]) ? INFINITY : wb[a + 3] + pad;
    }
    for (a = 0; a < 6; ++a)
        if (!isfinite(wb[a]))
            return 0;
    return 1;
}

/* The eigenvalues w and unit eigenvectors (columns of v) of the symmetric 3x3 matrix a, by cyclic Jacobi
 * rotations; a is overwritten. */
static inline void ig_sym3_eigen(double a[3][3], double w[3], double v[3][3])
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

#endif
