/* Ray-level stability of ig_shape_roots: a torus (a = 1, b = 0.4) hit by 1e5 random rays, each cast once
 * from 5 units and once from 1e4 units along the same line. Hit/miss decisions must agree, and hit points
 * must agree to 1e-9 (the torus has size ~1, so that is relative to the geometry). Also: the unshifted
 * expansion at the far origin (what the shift avoids) is measured and printed for the record, and
 * ig_shape_normal is checked at a regular and at a singular point. Exit status = number of failures. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "shape_torus_fixture.h"

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static double uniform(void) /* xorshift64*: deterministic, no global library state */
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ull) >> 11) * 0x1p-53;
}

int main(void)
{
    const ig_shape *sh = &shape_torus_fixture;
    const double params[2] = {1.0, 0.4};
    const int N = 100000;
    int failures = 0, hits = 0, disagree = 0, far_off = 0, naive_disagree = 0;
    double worst = 0.0;
    for (int i = 0; i < N; ++i) {
        double target[3], d[3];
        for (int k = 0; k < 3; ++k)
            target[k] = (uniform() * 2.0 - 1.0) * (k == 1 ? 0.5 : 1.5);
        double n2;
        do {
            for (int k = 0; k < 3; ++k)
                d[k] = uniform() * 2.0 - 1.0;
            n2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        } while (n2 > 1.0 || n2 < 1e-4);
        double len = sqrt(n2);
        for (int k = 0; k < 3; ++k)
            d[k] /= len;
        double on[3], of[3];
        for (int k = 0; k < 3; ++k) {
            on[k] = target[k] - 5.0 * d[k];
            of[k] = target[k] - 1e4 * d[k];
        }
        double rn[IG_MAX_DEGREE], rf[IG_MAX_DEGREE];
        int kn = ig_shape_roots(sh, params, on, d, 0.0, INFINITY, IG_ROOTS_AUTO, rn);
        int kf = ig_shape_roots(sh, params, of, d, 0.0, INFINITY, IG_ROOTS_AUTO, rf);
        if ((kn > 0) != (kf > 0)) {
            ++disagree;
            continue;
        }
        /* the same without the shift: coefficients expanded at the far origin, solved directly */
        double c[5], rr[IG_MAX_DEGREE];
        sh->coeffs(of, d, params, c);
        int kr = ig_real_roots(c, 4, 0.0, INFINITY, IG_ROOTS_AUTO, rr);
        if ((kr > 0) != (kn > 0))
            ++naive_disagree;
        if (kn == 0)
            continue;
        ++hits;
        double err = 0.0;
        for (int k = 0; k < 3; ++k) {
            double pn = on[k] + rn[0] * d[k], pf = of[k] + rf[0] * d[k];
            err = fmax(err, fabs(pn - pf));
        }
        if (err > worst)
            worst = err;
        if (err > 1e-9)
            ++far_off;
    }
    printf("torus rays: %d, hits: %d, hit/miss disagreements near vs 1e4: %d, hit points off by > 1e-9: %d, "
           "worst %.2e\n",
           N, hits, disagree, far_off, worst);
    printf("for the record, without the origin shift the far rays disagree with the near ones on %d rays\n",
           naive_disagree);
    if (disagree || far_off || hits < N / 10) {
        ++failures;
        fprintf(stderr, "FAIL far-away torus does not reproduce the near one\n");
    }

    double nrm[3], p[3] = {1.4, 0.0, 0.0};
    if (!ig_shape_normal(sh, params, p, nrm) || fabs(nrm[0] - 1.0) > 1e-15 || nrm[1] != 0.0 || nrm[2] != 0.0) {
        ++failures;
        fprintf(stderr, "FAIL normal at (1.4, 0, 0): %g %g %g\n", nrm[0], nrm[1], nrm[2]);
    }
    const double horn[2] = {1.0, 1.0}; /* a = b: the gradient vanishes at the centre */
    double z[3] = {0.0, 0.0, 0.0};
    if (ig_shape_normal(sh, horn, z, nrm) != 0 || nrm[0] != 0.0 || nrm[1] != 0.0 || nrm[2] != 0.0) {
        ++failures;
        fprintf(stderr, "FAIL singular normal: %g %g %g\n", nrm[0], nrm[1], nrm[2]);
    }
    double q[3] = {1e200, 1e200, 1e200}; /* gradient overflows to inf: still no NaN */
    int ok = ig_shape_normal(sh, params, q, nrm);
    if (isnan(nrm[0]) || isnan(nrm[1]) || isnan(nrm[2]) ||
        (ok && fabs(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2] - 1.0) > 1e-12)) {
        ++failures;
        fprintf(stderr, "FAIL normal at 1e200\n");
    }
    /* a ray that misses the box, a NaN ray, a zero direction */
    double o1[3] = {0.0, 5.0, 0.0}, d1[3] = {1.0, 0.0, 0.0}, dz[3] = {0.0, 0.0, 0.0}, on[3] = {NAN, 0.0, 0.0};
    double r[IG_MAX_DEGREE];
    if (ig_shape_roots(sh, params, o1, d1, 0.0, INFINITY, IG_ROOTS_AUTO, r) != 0 ||
        ig_shape_roots(sh, params, on, d1, 0.0, INFINITY, IG_ROOTS_AUTO, r) != 0 ||
        ig_shape_roots(sh, params, o1, dz, 0.0, INFINITY, IG_ROOTS_AUTO, r) != 0) {
        ++failures;
        fprintf(stderr, "FAIL degenerate rays gave roots\n");
    }
    /* through the hole along y: no hit; along x through the tube: 4 hits at known t */
    double o2[3] = {-5.0, 0.0, 0.0}, d2[3] = {2.0, 0.0, 0.0}; /* non-unit direction */
    int k = ig_shape_roots(sh, params, o2, d2, 0.0, INFINITY, IG_ROOTS_AUTO, r);
    double want[4] = {(5.0 - 1.4) / 2, (5.0 - 0.6) / 2, (5.0 + 0.6) / 2, (5.0 + 1.4) / 2};
    int good = k == 4;
    for (int i = 0; good && i < 4; ++i)
        good = fabs(r[i] - want[i]) <= 1e-14 * want[i];
    if (!good) {
        ++failures;
        fprintf(stderr, "FAIL ray along x: %d roots\n", k);
    }
    if (failures == 0)
        printf("test_shape_torus: all checks passed\n");
    return failures;
}
