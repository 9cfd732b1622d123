/* Ray-level stability of ig_shape_roots, and ig_shape_normal, as named cases (tests/c/ctest.h): a torus (a = 1,
 * b = 0.4) hit by 1e5 random rays, each cast once from 5 units and once from 1e4 units along the same line;
 * hit/miss decisions must agree, and hit points must agree to 1e-9 (the torus has size ~1, so that is relative
 * to the geometry). The unshifted expansion at the far origin (what the shift avoids) is measured and printed
 * for the record. The normal at a regular point, at a singular one and where the gradient overflows; rays
 * that cannot hit; a ray through the tube. Run under AddressSanitizer + UBSan by tests/test_c_drivers_roots.py,
 * each case reported by name. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "ctest.h"
#include "shape_torus_fixture.h"

static const double PARAMS[2] = {1.0, 0.4};

static double uniform(uint64_t *state) /* xorshift64*: deterministic, its state the caller's */
{
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    return (double)((*state * 2685821657736338717ull) >> 11) * 0x1p-53;
}

/* What the random rays found: near and far disagreeing on hit or miss, hit points apart, the unshifted solve
 * disagreeing with the near one. */
typedef struct {
    int hits, disagree, far_off, naive_disagree;
    double worst;
} far_tally;

/* A random line through the torus' box: a target point in it and a unit direction. */
static void random_line(uint64_t *rng, double target[3], double d[3])
{
    double n2, len;
    for (int k = 0; k < 3; ++k)
        target[k] = (uniform(rng) * 2.0 - 1.0) * (k == 1 ? 0.5 : 1.5);
    do {
        for (int k = 0; k < 3; ++k)
            d[k] = uniform(rng) * 2.0 - 1.0;
        n2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    } while (n2 > 1.0 || n2 < 1e-4);
    len = sqrt(n2);
    for (int k = 0; k < 3; ++k)
        d[k] /= len;
}

/* One line cast from 5 and from 1e4 units before its target, and the far one also solved without the shift. */
static void cast_near_and_far(const ig_shape *sh, uint64_t *rng, far_tally *c)
{
    double target[3], d[3], on[3], of[3], rn[IG_MAX_DEGREE], rf[IG_MAX_DEGREE], cf[5], rr[IG_MAX_DEGREE], err = 0.0;
    random_line(rng, target, d);
    for (int k = 0; k < 3; ++k) {
        on[k] = target[k] - 5.0 * d[k];
        of[k] = target[k] - 1e4 * d[k];
    }
    int kn = ig_shape_roots(sh, PARAMS, on, d, 0.0, INFINITY, IG_ROOTS_AUTO, rn);
    int kf = ig_shape_roots(sh, PARAMS, of, d, 0.0, INFINITY, IG_ROOTS_AUTO, rf);
    if ((kn > 0) != (kf > 0)) {
        ++c->disagree;
        return;
    }
    /* the same without the shift: coefficients expanded at the far origin, solved directly */
    sh->coeffs(of, d, PARAMS, cf);
    int kr = ig_real_roots(cf, 4, 0.0, INFINITY, IG_ROOTS_AUTO, rr);
    if ((kr > 0) != (kn > 0))
        ++c->naive_disagree;
    if (kn == 0)
        return;
    ++c->hits;
    for (int k = 0; k < 3; ++k)
        err = fmax(err, fabs((on[k] + rn[0] * d[k]) - (of[k] + rf[0] * d[k])));
    if (err > c->worst)
        c->worst = err;
    if (err > 1e-9)
        ++c->far_off;
}

static void far_torus_reproduces_the_near_one(ctest *t)
{
    const int N = 100000;
    uint64_t rng = 0x9E3779B97F4A7C15ull;
    far_tally c = {0, 0, 0, 0, 0.0};
    for (int i = 0; i < N; ++i)
        cast_near_and_far(&shape_torus_fixture, &rng, &c);
    printf("torus rays: %d, hits: %d, hit/miss disagreements near vs 1e4: %d, hit points off by > 1e-9: %d, "
           "worst %.2e\n",
           N, c.hits, c.disagree, c.far_off, c.worst);
    printf("for the record, without the origin shift the far rays disagree with the near ones on %d rays\n",
           c.naive_disagree);
    CHECKF(t, !(c.disagree || c.far_off || c.hits < N / 10), "far-away torus does not reproduce the near one");
}

static void normal_at_a_regular_point(ctest *t)
{
    double nrm[3], p[3] = {1.4, 0.0, 0.0};
    CHECKF(t,
           !(!ig_shape_normal(&shape_torus_fixture, PARAMS, p, nrm) || fabs(nrm[0] - 1.0) > 1e-15 || nrm[1] != 0.0 ||
             nrm[2] != 0.0),
           "normal at (1.4, 0, 0): %g %g %g", nrm[0], nrm[1], nrm[2]);
}

static void no_normal_at_the_singular_centre_of_a_horn_torus(ctest *t)
{
    const double horn[2] = {1.0, 1.0}; /* a = b: the gradient vanishes at the centre */
    double nrm[3], z[3] = {0.0, 0.0, 0.0};
    CHECKF(
        t,
        !(ig_shape_normal(&shape_torus_fixture, horn, z, nrm) != 0 || nrm[0] != 0.0 || nrm[1] != 0.0 || nrm[2] != 0.0),
        "singular normal: %g %g %g", nrm[0], nrm[1], nrm[2]);
}

static void no_nan_normal_where_the_gradient_overflows(ctest *t)
{
    double nrm[3], q[3] = {1e200, 1e200, 1e200}; /* gradient overflows to inf: still no NaN */
    int ok = ig_shape_normal(&shape_torus_fixture, PARAMS, q, nrm);
    CHECKF(t,
           !(isnan(nrm[0]) || isnan(nrm[1]) || isnan(nrm[2]) ||
             (ok && fabs(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2] - 1.0) > 1e-12)),
           "normal at 1e200");
}

/* a ray that misses the box, a NaN ray, a zero direction */
static void degenerate_rays_give_no_roots(ctest *t)
{
    const ig_shape *sh = &shape_torus_fixture;
    double o1[3] = {0.0, 5.0, 0.0}, d1[3] = {1.0, 0.0, 0.0}, dz[3] = {0.0, 0.0, 0.0}, on[3] = {NAN, 0.0, 0.0};
    double r[IG_MAX_DEGREE];
    CHECKF(t,
           !(ig_shape_roots(sh, PARAMS, o1, d1, 0.0, INFINITY, IG_ROOTS_AUTO, r) != 0 ||
             ig_shape_roots(sh, PARAMS, on, d1, 0.0, INFINITY, IG_ROOTS_AUTO, r) != 0 ||
             ig_shape_roots(sh, PARAMS, o1, dz, 0.0, INFINITY, IG_ROOTS_AUTO, r) != 0),
           "degenerate rays gave roots");
}

/* along x through the tube, a non-unit direction: 4 hits at known t */
static void ray_along_x_meets_the_tube_four_times(ctest *t)
{
    double o2[3] = {-5.0, 0.0, 0.0}, d2[3] = {2.0, 0.0, 0.0}, r[IG_MAX_DEGREE];
    int k = ig_shape_roots(&shape_torus_fixture, PARAMS, o2, d2, 0.0, INFINITY, IG_ROOTS_AUTO, r);
    double want[4] = {(5.0 - 1.4) / 2, (5.0 - 0.6) / 2, (5.0 + 0.6) / 2, (5.0 + 1.4) / 2};
    int good = k == 4;
    for (int i = 0; good && i < 4; ++i)
        good = fabs(r[i] - want[i]) <= 1e-14 * want[i];
    CHECKF(t, good, "ray along x: %d roots", k);
}

static const ctest_case CASES[] = {
    CTEST_CASE(far_torus_reproduces_the_near_one),
    CTEST_CASE(normal_at_a_regular_point),
    CTEST_CASE(no_normal_at_the_singular_centre_of_a_horn_torus),
    CTEST_CASE(no_nan_normal_where_the_gradient_overflows),
    CTEST_CASE(degenerate_rays_give_no_roots),
    CTEST_CASE(ray_along_x_meets_the_tube_four_times),
};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
