/* Timing entry points for `implgen bench solvers`: the solver report measures time in C, not in Python. */
#define _POSIX_C_SOURCE 199309L
#include "roots_impl.h"

#include <math.h>
#include <time.h>

/* First-root twin of ig_bench_solve_batch (declared here: only the bench's ctypes binding calls it). */
double ig_bench_first_batch(const double *c, int n, long count, const double *lo, const double *hi, int method,
                            double *roots, int *counts, double *ns);

static double now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

/* Median of the cost of an empty timed region (two clock reads), subtracted from every solve. */
static double clock_overhead(void)
{
    enum { N = 2001 };
    double d[N];
    for (int i = 0; i < N; ++i) {
        double t0 = now_ns();
        double t1 = now_ns();
        d[i] = t1 - t0;
    }
    ig_sort(d, N); /* insertion sort is fine for this size, once */
    return d[N / 2];
}

/* One timed pass (a clock read either side of every solve) and one untimed pass (throughput; the checksum
 * keeps the work from being optimised away). first != 0: ig_first_root's path (at most one root each, so
 * `roots` holds `count` entries); else all roots (`roots` holds count * n, NaN-padded). */
static double bench_batch(const double *c, int n, long count, const double *lo, const double *hi, int method, int first,
                          double *roots, int *counts, double *ns)
{
    double r[IG_MAX_DEGREE];
    double over = clock_overhead();
    const int width = first ? 1 : n;
    for (long i = 0; i < count; ++i) {
        double t0 = now_ns();
        int k = ig_roots_core(c + i * (n + 1), n, lo[i], hi[i], method, first, r);
        double t1 = now_ns();
        ns[i] = (t1 - t0) - over;
        counts[i] = k;
        for (int j = 0; j < width; ++j)
            roots[i * width + j] = j < k ? r[j] : NAN;
    }
    volatile double sink = 0.0;
    double t0 = now_ns();
    for (long i = 0; i < count; ++i) {
        int k = ig_roots_core(c + i * (n + 1), n, lo[i], hi[i], method, first, r);
        sink += k > 0 ? r[0] : 0.0;
    }
    double t1 = now_ns();
    (void)sink;
    return t1 - t0;
}

double ig_bench_solve_batch(const double *c, int n, long count, const double *lo, const double *hi, int method,
                            double *roots, int *counts, double *ns)
{
    return bench_batch(c, n, count, lo, hi, method, 0, roots, counts, ns);
}

/* ig_first_root timed as above: the nearest root only (or none) per polynomial into roots[i] (NaN if none),
 * 0/1 into counts[i]. Returns the untimed pass's total ns. */
double ig_bench_first_batch(const double *c, int n, long count, const double *lo, const double *hi, int method,
                            double *roots, int *counts, double *ns)
{
    return bench_batch(c, n, count, lo, hi, method, 1, roots, counts, ns);
}

/* Bernstein pieces handed to bracketing, per polynomial (untimed): fb[i] for polynomial i, in first-root mode
 * when first != 0. */
void ig_bench_fallbacks(const double *c, int n, long count, const double *lo, const double *hi, int method, int first,
                        int *fb);

void ig_bench_fallbacks(const double *c, int n, long count, const double *lo, const double *hi, int method, int first,
                        int *fb)
{
    double r[IG_MAX_DEGREE];
    for (long i = 0; i < count; ++i) {
        fb[i] = 0;
        ig_roots_stats(c + i * (n + 1), n, lo[i], hi[i], method, first, &fb[i], r);
    }
}
