/* Per-ray cost of a generated intersector, split into coefficients / solve / total (bench/povray_compare.py).
 * Compiled once per surface with -DSHAPE_SYM=<name>_shape. Rays start on a sphere around the shape's box and
 * aim at uniform points inside it, so every ray enters the box. Times are the median of `reps` passes. */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "shape.h"

extern const ig_shape SHAPE_SYM;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static unsigned long long rng_state;
static double urand(void)
{
    rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* out: [0] ns/ray coefficients, [1] ns/ray solve, [2] ns/ray total (ig_shape_roots), [3] mean roots per ray,
 * [4] fraction of rays with a root. Returns 0 on success. */
int degree_cost(int n, int reps, unsigned long long seed, double *out)
{
    const ig_shape *s = &SHAPE_SYM;
    int deg = s->degree, i, r, k;
    double box[6], ctr[3], rad = 0.0, roots[IG_MAX_DEGREE];
    double *o = malloc(sizeof(double) * 3 * (size_t)n), *d = malloc(sizeof(double) * 3 * (size_t)n);
    double *o2 = malloc(sizeof(double) * 3 * (size_t)n), *lo = malloc(sizeof(double) * (size_t)n);
    double *hi = malloc(sizeof(double) * (size_t)n), *c = malloc(sizeof(double) * (size_t)(deg + 1) * (size_t)n);
    double *tc = malloc(sizeof(double) * (size_t)reps), *ts = malloc(sizeof(double) * (size_t)reps);
    double *tt = malloc(sizeof(double) * (size_t)reps);
    long total_roots = 0, hit = 0;
    volatile double sink = 0.0;
    if (!o || !d || !o2 || !lo || !hi || !c || !tc || !ts || !tt || !s->bounds(NULL, box))
        return 1;
    rng_state = seed;
    for (k = 0; k < 3; ++k) {
        ctr[k] = 0.5 * (box[k] + box[3 + k]);
        rad += (box[3 + k] - box[k]) * (box[3 + k] - box[k]);
    }
    rad = 1.5 * sqrt(rad);
    for (i = 0; i < n; ++i) {
        double u = 2.0 * urand() - 1.0, phi = 6.283185307179586 * urand(), sq = sqrt(1.0 - u * u);
        double dir[3] = {sq * cos(phi), sq * sin(phi), u}, t0 = -INFINITY, t1 = INFINITY, num = 0, den = 0, tsh;
        for (k = 0; k < 3; ++k) {
            double target = box[k] + (box[3 + k] - box[k]) * urand();
            o[3 * i + k] = ctr[k] + rad * dir[k];
            d[3 * i + k] = target - o[3 * i + k];
        }
        for (k = 0; k < 3; ++k) { /* slab clip: the same interval ig_shape_roots solves on */
            double a = (box[k] - o[3 * i + k]) / d[3 * i + k], b = (box[3 + k] - o[3 * i + k]) / d[3 * i + k];
            if (a > b) {
                double t = a;
                a = b;
                b = t;
            }
            if (a > t0)
                t0 = a;
            if (b < t1)
                t1 = b;
            num += d[3 * i + k] * (ctr[k] - o[3 * i + k]);
            den += d[3 * i + k] * d[3 * i + k];
        }
        if (t0 < 0.0)
            t0 = 0.0;
        tsh = num / den;
        tsh = tsh < t0 ? t0 : (tsh > t1 ? t1 : tsh);
        for (k = 0; k < 3; ++k)
            o2[3 * i + k] = o[3 * i + k] + tsh * d[3 * i + k];
        lo[i] = t0 - tsh;
        hi[i] = t1 - tsh;
    }
    for (r = 0; r < reps; ++r) {
        double t = now();
        for (i = 0; i < n; ++i)
            s->coeffs(o2 + 3 * i, d + 3 * i, NULL, c + (size_t)(deg + 1) * (size_t)i);
        tc[r] = now() - t;
        t = now();
        total_roots = 0;
        for (i = 0; i < n; ++i) {
            int m = ig_real_roots(c + (size_t)(deg + 1) * (size_t)i, deg, lo[i], hi[i], IG_ROOTS_AUTO, roots);
            total_roots += m;
            if (m)
                sink += roots[0];
        }
        ts[r] = now() - t;
        t = now();
        hit = 0;
        for (i = 0; i < n; ++i) {
            int m = ig_shape_roots(s, NULL, o + 3 * i, d + 3 * i, 0.0, INFINITY, IG_ROOTS_AUTO, roots);
            hit += m > 0;
            if (m)
                sink += roots[0];
        }
        tt[r] = now() - t;
    }
    qsort(tc, (size_t)reps, sizeof(double), cmp);
    qsort(ts, (size_t)reps, sizeof(double), cmp);
    qsort(tt, (size_t)reps, sizeof(double), cmp);
    out[0] = 1e9 * tc[reps / 2] / n;
    out[1] = 1e9 * ts[reps / 2] / n;
    out[2] = 1e9 * tt[reps / 2] / n;
    out[3] = (double)total_roots / n;
    out[4] = (double)hit / n;
    free(o);
    free(d);
    free(o2);
    free(lo);
    free(hi);
    free(c);
    free(tc);
    free(ts);
    free(tt);
    (void)sink;
    return 0;
}
