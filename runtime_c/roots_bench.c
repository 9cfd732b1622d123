/* Timing entry point for `implgen bench solvers`: the solver report measures time in C, not in Python. */
#define _POSIX_C_SOURCE 199309L
#include "roots_impl.h"

#include <math.h>
#include <time.h>

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
    /* partial selection of the median (insertion sort is fine for this size, once) */
    for (int i = 1; i < N; ++i) {
        double x = d[i];
        int j = i - 1;
        while (j >= 0 && d[j] > x) {
            d[j + 1] = d[j];
            --j;
        }
        d[j + 1] = x;
    }
    return d[N / 2];
}

double ig_bench_solve_batch(const double *c, int n, long count, const double *lo, const double *hi, int method,
                            double *roots, int *counts, double *ns)
{
    double r[IG_MAX_DEGREE];
    double over = clock_overhead();
    for (long i = 0; i < count; ++i) {
        double t0 = now_ns();
        int k = ig_real_roots_any(c + i * (n + 1), n, lo[i], hi[i], method, r);
        double t1 = now_ns();
        ns[i] = (t1 - t0) - over;
        counts[i] = k;
        for (int j = 0; j < n; ++j)
            roots[i * n + j] = j < k ? r[j] : NAN;
    }
    /* throughput: one untimed pass, total wall time; the checksum keeps the work from being optimised away */
    volatile double sink = 0.0;
    double t0 = now_ns();
    for (long i = 0; i < count; ++i) {
        int k = ig_real_roots_any(c + i * (n + 1), n, lo[i], hi[i], method, r);
        sink += k > 0 ? r[0] : 0.0;
    }
    double t1 = now_ns();
    (void)sink;
    return t1 - t0;
}
