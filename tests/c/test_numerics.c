/* One named test per helper of runtime_c/numerics.h, its hard case among them (tests/test_c_cases.py runs
 * them under ASan + UBSan and reports each by name). The expected values are exact: dyadic numbers whose sums
 * and products double holds, or identities that hold to the last bit. */
#include <float.h>
#include <math.h>
#include <string.h>

#include "ctest.h"
#include "numerics.h"

static int near(double a, double b, double tol) { return fabs(a - b) <= tol; }

/* ------------------------------------------------------------------ error-free transformations */

static void two_sum_is_exact(ctest *t)
{
    double s, e;
    ig_two_sum(1.0, 0x1p-60, &s, &e); /* the small one lost in fl(a + b), kept whole in e */
    CHECK(t, s == 1.0 && e == 0x1p-60);
    ig_two_sum(0x1p-60, 1.0, &s, &e); /* either order: no condition on the magnitudes (Fast2Sum needs one) */
    CHECK(t, s == 1.0 && e == 0x1p-60);
    ig_two_sum(0x1p53, 1.0, &s, &e); /* a tie, rounded to even: 2^53 + 1 = 2^53 + 1 */
    CHECK(t, s == 0x1p53 && e == 1.0);
    ig_two_sum(1.5, -1.5, &s, &e); /* exact cancellation */
    CHECK(t, s == 0.0 && e == 0.0);
    ig_two_sum(-0x1p-1074, 0x1p1023, &s, &e); /* the smallest subnormal against the largest power of two */
    CHECK(t, s == 0x1p1023 && e == -0x1p-1074);
}

static void two_prod_is_exact(ctest *t)
{
    double p, e, a = 1.0 + 0x1p-30;
    ig_two_prod(a, a, &p, &e); /* (1 + 2^-30)^2 = 1 + 2^-29 + 2^-60: the last term only in e */
    CHECK(t, p == 1.0 + 0x1p-29 && e == 0x1p-60);
    ig_two_prod(-a, a, &p, &e);
    CHECK(t, p == -(1.0 + 0x1p-29) && e == -0x1p-60);
    ig_two_prod(0x1p500 * a, 0x1p-700 * a, &p, &e); /* far from 1, within Dekker's range (below 2^996) */
    CHECK(t, p == 0x1p-200 * (1.0 + 0x1p-29) && e == 0x1p-260);
    ig_two_prod(3.0, 0.1, &p, &e); /* the rounding of 3 * fl(0.1): p + e is the product exactly */
    CHECK(t, p == 3.0 * 0.1 && e != 0.0 && fabs(e) <= 0.5 * DBL_EPSILON * fabs(p));
}

static void max_ignores_a_nan_in_its_second_argument(ctest *t)
{
    CHECK(t, ig_max(1.0, 2.0) == 2.0 && ig_max(2.0, 1.0) == 2.0);
    CHECK(t, ig_max(1.0, NAN) == 1.0);
    CHECK(t, isnan(ig_max(NAN, 1.0))); /* only b's NaN is ignored, as documented */
    CHECK(t, ig_max(-INFINITY, -1e308) == -1e308 && ig_max(1.0, INFINITY) == INFINITY);
}

/* ------------------------------------------------------------------ Horner's rule */

static void horner_evaluates_lowest_power_first(ctest *t)
{
    const double c[] = {1.0, -2.0, 3.0}, k[] = {7.5};
    CHECK(t, ig_horner(c, 2, 2.0) == 1.0 - 4.0 + 12.0);
    CHECK(t, ig_horner(c, 2, 0.0) == 1.0);
    CHECK(t, ig_horner(k, 0, 1e300) == 7.5); /* degree 0: the constant, x never multiplied */
    CHECK(t, ig_horner(c, 2, -0.5) == 1.0 + 1.0 + 0.75);
}

static void horner_abs_bounds_the_rounding_scale(ctest *t)
{
    const double c[] = {1.0, -2.0, 3.0, -0.5};
    double x = 2.0, v = ig_horner_abs(c, 3, x);
    CHECK(t, v == 1.0 + 4.0 + 12.0 + 4.0);
    CHECK(t, v >= fabs(ig_horner(c, 3, x)) && v >= fabs(ig_horner(c, 3, -x)));
    CHECK(t, ig_horner_abs(c, 3, 0.0) == 1.0);
}

/* (x - 1)^7 expanded, near its 7-fold root: the condition number is ((x + 1) / (x - 1))^7 ~ 1.3e16 at x = 1.01,
 * so plain Horner loses every digit while compensated Horner keeps about u + 1e16 u^2 ~ 2e-16. The reference:
 * x - 1 is exact in double (Sterbenz), and its 7th power is good to 7 roundings. */
static void horner_compensated_near_a_multiple_root(ctest *t)
{
    const double c[] = {-1.0, 7.0, -21.0, 35.0, -35.0, 21.0, -7.0, 1.0};
    double x = 1.01, dx = x - 1.0, exact = dx * dx * dx * dx * dx * dx * dx;
    double plain = ig_horner(c, 7, x), comp = ig_horner_compensated(c, 7, x);
    CHECK(t, fabs(comp - exact) <= 1e-13 * exact);
    CHECK(t, fabs(plain - exact) > 1e-3 * exact); /* the hard case is hard */
    CHECK(t, ig_horner_compensated(c, 7, 1.0) == 0.0);
    CHECK(t, ig_horner_compensated(c, 0, 5.0) == -1.0);
}

/* ------------------------------------------------------------------ slab test */

static void slab_orders_its_ends_and_says_when_it_swapped(ctest *t)
{
    double ta, tb;
    CHECK(t, ig_slab(-1.0, 3.0, 1.0, 1.0 / 2.0, &ta, &tb) == 0 && ta == -1.0 && tb == 1.0);
    CHECK(t, ig_slab(-1.0, 3.0, 1.0, 1.0 / -4.0, &ta, &tb) == 1 && ta == -0.5 && tb == 0.5); /* enters at hi */
    /* a ray parallel to the slab: inv = +-inf, both ends infinite of one sign outside, of both inside */
    CHECK(t, ig_slab(-1.0, 1.0, 0.0, INFINITY, &ta, &tb) == 0 && ta == -INFINITY && tb == INFINITY);
    ig_slab(-1.0, 1.0, 2.0, INFINITY, &ta, &tb);
    CHECK(t, ta == -INFINITY && tb == -INFINITY);
    CHECK(t, ig_slab(NAN, 1.0, 0.0, 1.0, &ta, &tb) == 0 && isnan(ta) && tb == 1.0); /* NaN plane: NaN end */
}

/* ------------------------------------------------------------------ affine maps */

/* A map with a rotation about z by 90 degrees, scales 2, 3, 4 and a translation: exact in double. */
static const double M[12] = {0, -3, 0, 10, 2, 0, 0, 20, 0, 0, 4, 30};

static void affine_point_and_vector_apply_the_map(ctest *t)
{
    double p[3] = {1, 2, 3}, out[3];
    ig_affine_point(M, p, out);
    CHECK(t, out[0] == 4 && out[1] == 22 && out[2] == 42);
    ig_affine_vector(M, p, out);
    CHECK(t, out[0] == -6 && out[1] == 2 && out[2] == 12);
    ig_affine_point(M, p, p); /* out may alias the input */
    CHECK(t, p[0] == 4 && p[1] == 22 && p[2] == 42);
    p[0] = 1, p[1] = 2, p[2] = 3;
    ig_affine_vector(M, p, p);
    CHECK(t, p[0] == -6 && p[1] == 2 && p[2] == 12);
}

static void affine_invert_round_trips_and_refuses_singular_maps(ctest *t)
{
    double inv[12], back[3], p[3] = {1.25, -2.5, 7}, q[3], keep[12];
    int i;
    CHECK(t, ig_affine_invert(M, inv));
    ig_affine_point(M, p, q);
    ig_affine_point(inv, q, back);
    for (i = 0; i < 3; ++i)
        CHECK(t, back[i] == p[i]); /* powers of two and 3: exact here */
    {                              /* the hard case: singular, and nearly so at 1e-12 of the scale cubed */
        double flat[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0},
               thin[12] = {1e6, 0, 0, 0, 0, 1e6, 0, 0, 0, 0, 0x1p-20, 0};
        double bad[12] = {1, 0, 0, 0, 0, NAN, 0, 0, 0, 0, 1, 0}, zero[12] = {0};
        for (i = 0; i < 12; ++i)
            inv[i] = keep[i] = (double)i;
        CHECK(t, !ig_affine_invert(flat, inv) && !ig_affine_invert(bad, inv) && !ig_affine_invert(zero, inv));
        CHECK(t, !ig_affine_invert(thin, inv));       /* det 9.5e5 <= 1e-12 * (1e6)^3 */
        CHECK(t, memcmp(inv, keep, sizeof inv) == 0); /* refused: untouched */
        thin[10] = 0x1p-19;                           /* det 1.9e6 > 1e6: the other side of the threshold */
        CHECK(t, ig_affine_invert(thin, inv) && inv[0] == 1e-6 && inv[10] == 0x1p19);
    }
}

static void unit_vector_gives_the_length_and_leaves_u_alone_without_one(ctest *t)
{
    double v[3] = {3, 0, -4}, u[3] = {9, 9, 9}, zero[3] = {0, 0, 0}, huge[3] = {1e300, 1e300, 0}, w[3] = {9, 9, 9};
    CHECK(t, ig_unit_vector(v, u) == 5.0 && u[0] == 0.6 && u[1] == 0.0 && u[2] == -0.8);
    CHECK(t, ig_unit_vector(zero, w) == 0.0 && w[0] == 9 && w[1] == 9 && w[2] == 9); /* no direction: untouched */
    CHECK(t, isinf(ig_unit_vector(huge, w)) && w[0] == 9); /* |v|^2 overflows: untouched, the caller checks L */
}

static void affine_unit_ray_gives_the_object_space_length(ctest *t)
{
    double inv[12], o[3] = {10, 20, 30}, d[3] = {0, 0, 8}, oo[3], u[3] = {9, 9, 9}, L;
    CHECK(t, ig_affine_invert(M, inv));
    L = ig_affine_unit_ray(inv, o, d, oo, u); /* z is scaled by 4: a world step of 8 is 2 in object space */
    CHECK(t, L == 2.0 && u[0] == 0 && u[1] == 0 && u[2] == 1 && oo[0] == 0 && oo[1] == 0 && oo[2] == 0);
    L = ig_affine_unit_ray(NULL, o, d, oo, u); /* NULL: the identity */
    CHECK(t, L == 8.0 && u[2] == 1.0 && oo[0] == 10 && oo[1] == 20 && oo[2] == 30);
    {
        double zero[3] = {0, 0, 0}, big[3] = {1e300, 1e300, 0}, w[3] = {9, 9, 9};
        CHECK(t, ig_affine_unit_ray(NULL, o, zero, oo, w) == 0.0 && w[0] == 9); /* u untouched */
        CHECK(t, isinf(ig_affine_unit_ray(NULL, o, big, oo, w)) && w[0] == 9);  /* |d|^2 overflows */
    }
}

static void affine_normal_maps_by_the_inverse_transpose(ctest *t)
{
    /* the unit sphere scaled by (2, 1, 1): at the object point (1, 1, 0)/sqrt 2, world (sqrt 2, 1/sqrt 2, 0), the
     * world normal is grad (x^2/4 + y^2) = (x/2, 2y) there, i.e. along (1/sqrt 2, sqrt 2, 0) ~ (1, 2, 0) */
    double m[12] = {2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}, inv[12], g[3] = {1, 1, 0}, n[3];
    CHECK(t, ig_affine_invert(m, inv));
    CHECK(t, ig_affine_normal(inv, g, n));
    CHECK(t, near(n[0], 1.0 / sqrt(5.0), 1e-15) && near(n[1], 2.0 / sqrt(5.0), 1e-15) && n[2] == 0.0);
    g[0] = g[1] = g[2] = 0.0; /* a singular point: no normal */
    CHECK(t, !ig_affine_normal(inv, g, n));
}

static void affine_box_holds_the_corners_and_keeps_open_sides_open(ctest *t)
{
    const double unit[6] = {-1, -1, -1, 1, 1, 1};
    double wb[6];
    int a;
    CHECK(t, ig_affine_box(M, unit, wb));
    { /* x = -3y + 10 in [7, 13], y = 2x + 20 in [18, 22], z = 4z + 30 in [26, 34]; padded by 1e-9 of size */
        const double want[6] = {7, 18, 26, 13, 22, 34};
        for (a = 0; a < 6; ++a)
            CHECK(t, (a < 3 ? wb[a] < want[a] : wb[a] > want[a]) && near(wb[a], want[a], 1e-7));
    }
    { /* the hard case: an open object axis (x) reaches world y only; world x and z stay finite */
        const double open[6] = {-INFINITY, -1, -1, INFINITY, 1, 1};
        CHECK(t, !ig_affine_box(M, open, wb));
        CHECK(t, wb[1] == -INFINITY && wb[4] == INFINITY);
        CHECK(t, near(wb[0], 7, 1e-6) && near(wb[3], 13, 1e-6) && near(wb[2], 26, 1e-6) && near(wb[5], 34, 1e-6));
    }
    { /* a map mixing an open axis into a world axis from both signs: inf - inf is open, never empty */
        const double open[6] = {-INFINITY, -1, -1, INFINITY, 1, 1}, mix[12] = {1, 0, 0, 0, -1, 1, 0, 0, 0, 0, 1, 0};
        ig_affine_box(mix, open, wb);
        CHECK(t, wb[0] == -INFINITY && wb[3] == INFINITY && wb[1] == -INFINITY && wb[4] == INFINITY);
        CHECK(t, near(wb[2], -1, 1e-8) && near(wb[5], 1, 1e-8));
    }
}

/* ------------------------------------------------------------------ symmetric 3x3 eigen-decomposition */

/* A v_k = w_k v_k with the columns of v orthonormal, against the matrix before it was overwritten. */
static void check_eigen(ctest *t, const double a0[3][3], const double w[3], double v[3][3], double tol)
{
    int i, j, k;
    double scale = 0.0;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            scale = fmax(scale, fabs(a0[i][j]));
    for (k = 0; k < 3; ++k)
        for (i = 0; i < 3; ++i) {
            double av = a0[i][0] * v[0][k] + a0[i][1] * v[1][k] + a0[i][2] * v[2][k];
            CHECK(t, near(av, w[k] * v[i][k], tol * scale));
        }
    for (k = 0; k < 3; ++k)
        for (j = 0; j < 3; ++j) {
            double dot = v[0][k] * v[0][j] + v[1][k] * v[1][j] + v[2][k] * v[2][j];
            CHECK(t, near(dot, k == j, 1e-14));
        }
}

static void sym3_eigen_decomposes_symmetric_matrices(ctest *t)
{
    const double a0[3][3] = {{2, 1, 0}, {1, 2, 0}, {0, 0, 3}}; /* eigenvalues 1, 3, 3 */
    double a[3][3], w[3], v[3][3], sorted[3];
    memcpy(a, a0, sizeof a);
    ig_sym3_eigen(a, w, v);
    check_eigen(t, a0, w, v, 1e-15);
    memcpy(sorted, w, sizeof sorted);
    for (int i = 0; i < 3; ++i) /* the eigenvalues as a set */
        for (int j = i + 1; j < 3; ++j)
            if (sorted[j] < sorted[i]) {
                double x = sorted[i];
                sorted[i] = sorted[j];
                sorted[j] = x;
            }
    CHECK(t, near(sorted[0], 1, 1e-15) && near(sorted[1], 3, 1e-15) && near(sorted[2], 3, 1e-15));
    {
        const double d0[3][3] = {{5, 0, 0}, {0, -1, 0}, {0, 0, 0}}; /* already diagonal: the identity's columns */
        memcpy(a, d0, sizeof a);
        ig_sym3_eigen(a, w, v);
        CHECK(t, w[0] == 5 && w[1] == -1 && w[2] == 0 && v[0][0] == 1 && v[1][1] == 1 && v[2][2] == 1);
    }
}

/* The hard case: an off-diagonal entry so small against the diagonal's gap that theta^2 overflows, and a
 * matrix of rank one (the dual-contouring vertex of a flat patch). */
static void sym3_eigen_survives_overflowing_rotations(ctest *t)
{
    const double a0[3][3] = {{1e200, 1e-200, 0}, {1e-200, -1e200, 0}, {0, 0, 1}};
    const double r0[3][3] = {{1, 2, 2}, {2, 4, 4}, {2, 4, 4}}; /* n n^T, n = (1, 2, 2): eigenvalues 9, 0, 0 */
    double a[3][3], w[3], v[3][3];
    memcpy(a, a0, sizeof a);
    ig_sym3_eigen(a, w, v);
    for (int k = 0; k < 3; ++k)
        CHECK(t, isfinite(w[k]) && isfinite(v[0][k]) && isfinite(v[1][k]) && isfinite(v[2][k]));
    check_eigen(t, a0, w, v, 1e-15);
    memcpy(a, r0, sizeof a);
    ig_sym3_eigen(a, w, v);
    check_eigen(t, r0, w, v, 1e-14);
    CHECK(t, near(w[0] + w[1] + w[2], 9, 1e-13) && near(fmax(w[0], fmax(w[1], w[2])), 9, 1e-13));
}

static const ctest_case CASES[] = {
    CTEST_CASE(two_sum_is_exact),
    CTEST_CASE(two_prod_is_exact),
    CTEST_CASE(max_ignores_a_nan_in_its_second_argument),
    CTEST_CASE(horner_evaluates_lowest_power_first),
    CTEST_CASE(horner_abs_bounds_the_rounding_scale),
    CTEST_CASE(horner_compensated_near_a_multiple_root),
    CTEST_CASE(slab_orders_its_ends_and_says_when_it_swapped),
    CTEST_CASE(affine_point_and_vector_apply_the_map),
    CTEST_CASE(affine_invert_round_trips_and_refuses_singular_maps),
    CTEST_CASE(unit_vector_gives_the_length_and_leaves_u_alone_without_one),
    CTEST_CASE(affine_unit_ray_gives_the_object_space_length),
    CTEST_CASE(affine_normal_maps_by_the_inverse_transpose),
    CTEST_CASE(affine_box_holds_the_corners_and_keeps_open_sides_open),
    CTEST_CASE(sym3_eigen_decomposes_symmetric_matrices),
    CTEST_CASE(sym3_eigen_survives_overflowing_rotations),
};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
