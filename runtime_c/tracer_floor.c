/* The floor report's C side (bench/floor.py): what the rays of a render cost at the least, timed with the same
 * compiled shapes as the render.
 *
 * An instrumented build of the library (-DRT_TRACE) records, during a one-thread render, every scene query
 * (the ray's kind, the ray, its range, the query mode) and every leaf solve whose ray enters the leaf's box (the
 * kind, the leaf, the object-space ray, the clipped range and the roots found); see the hooks in
 * tracer_internal.h. The ordinary build then times over those records:
 *  - rt_floor_time: the floor -- for each box entry, the ray polynomial's coefficients at the point the solve
 *    expands them around (shape.c's shift point) and one Newton step at each root the solve kept (Horner's
 *    value and derivative, one division);
 *  - rt_replay_time: the same queries through rt_scene_closest, the real work of finding those hits.
 * Both count the calling thread's CPU time (on a shared machine, time another process had the core is not theirs).
 * Without RT_TRACE only these two timing functions are compiled; the render loop does not call them.
 */
#define _POSIX_C_SOURCE 199309L /* clock_gettime */
#include "roots_impl.h"
#include "tracer_internal.h"

#include <stdlib.h>
#include <time.h>

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The floor of one recorded box entry (si: kind, leaf, mode, root count; sd: o, u, lo, hi): the coefficients and
 * one Newton step per root. Returns the sum of the polished roots (kept so that nothing is optimised away). */
static double floor_one(const rt_scene *s, const int *si, const double *sd, const double *roots)
{
    const rt_node *n = &s->nodes[si[1]];
    double c[IG_MAX_DEGREE + 1], os[3], ts = 0.0, acc = 0.0;
    int a, k;
    if (si[2] != RT_TRACE_PLANE)
        ts = ig_shape_shift_point(&n->prep, sd, sd + 3, sd[6], sd[7]);
    for (a = 0; a < 3; ++a)
        os[a] = sd[a] + ts * sd[3 + a];
    n->shape->coeffs(os, sd + 3, n->params, c);
    for (k = 0; k < si[3]; ++k) {
        double x = roots[k] - ts, p, dp;
        ig_horner2(c, n->shape->degree, x, &p, &dp);
        acc += x - p / dp;
    }
    return acc + c[0];
}

/* CPU seconds taken by the floor of the recorded box entries of one kind (all kinds when kind < 0): n entries, 4 ints
 * and 8 doubles each, their roots one after the other in roots. *sink receives a sum of the results. */
double rt_floor_time(const rt_scene *s, long n, const int *si, const double *sd, const double *roots, int kind,
                     double *sink)
{
    double t0 = now_seconds(), acc = 0.0;
    long i, off = 0;
    for (i = 0; i < n; ++i) {
        if (kind < 0 || si[4 * i] == kind)
            acc += floor_one(s, si + 4 * i, sd + 8 * i, roots + off);
        off += si[4 * i + 3];
    }
    *sink = acc;
    return now_seconds() - t0;
}

/* CPU seconds taken by the recorded scene queries of one kind (all when kind < 0) through rt_scene_closest: n queries,
 * 3 ints (kind, mode, skip) and 8 doubles (o, d, tmin, tmax) each. *found receives how many found a hit. */
double rt_replay_time(const rt_scene *s, long n, const int *qi, const double *qd, int kind, long *found)
{
    double t0 = now_seconds();
    long i, hits = 0;
    for (i = 0; i < n; ++i) {
        rt_pending p;
        const double *q = qd + 8 * i;
        if (kind >= 0 && qi[3 * i] != kind)
            continue;
        hits += rt_scene_closest(s, q, q + 3, q[6], q[7], qi[3 * i + 1], qi[3 * i + 2], &p);
    }
    *found = hits;
    return now_seconds() - t0;
}

#ifdef RT_TRACE
/* ---- the instrumented build's recorder ---- */

typedef struct rt_trace_log {
    int kind; /* the kind (RT_RAYS_*) of the rays being traced now */
    int full; /* an allocation failed: the log stopped growing */
    long nq, capq, ns, caps, nr, capr;
    int *qi;       /* per query: kind, mode, skip */
    double *qd;    /* per query: o, d, tmin, tmax */
    int *si;       /* per box entry: kind, leaf, mode, root count */
    double *sd;    /* per box entry: o, u, lo, hi (the clipped range) */
    double *roots; /* every entry's roots, in order */
} rt_trace_log;

rt_trace_log *rt_trace_new(void) { return calloc(1, sizeof(rt_trace_log)); }

void rt_trace_free(rt_trace_log *log)
{
    if (!log)
        return;
    free(log->qi);
    free(log->qd);
    free(log->si);
    free(log->sd);
    free(log->roots);
    free(log);
}

/* Records the renders of s into log from now on (log NULL: no longer). */
void rt_trace_attach(rt_scene *s, rt_trace_log *log) { s->trace = log; }

/* Queries, box entries and roots recorded so far. */
void rt_trace_sizes(const rt_trace_log *log, long out[3])
{
    out[0] = log->nq;
    out[1] = log->ns;
    out[2] = log->nr;
}

/* Copies the records into arrays of the sizes rt_trace_sizes gives (3 and 8 per query, 4 and 8 per entry). */
void rt_trace_copy(const rt_trace_log *log, int *qi, double *qd, int *si, double *sd, double *roots)
{
    memcpy(qi, log->qi, (size_t)log->nq * 3 * sizeof(int));
    memcpy(qd, log->qd, (size_t)log->nq * 8 * sizeof(double));
    memcpy(si, log->si, (size_t)log->ns * 4 * sizeof(int));
    memcpy(sd, log->sd, (size_t)log->ns * 8 * sizeof(double));
    memcpy(roots, log->roots, (size_t)log->nr * sizeof(double));
}

/* Room for one more item of `ints` ints and `dbls` doubles in the arrays *pi and *pd of *cap items. */
static int room(rt_trace_log *log, long n, long *cap, int **pi, int ints, double **pd, int dbls)
{
    long ncap;
    void *a, *b;
    if (log->full)
        return 0;
    if (n < *cap)
        return 1;
    ncap = *cap ? 2 * *cap : 4096;
    a = realloc(*pi, (size_t)ncap * (size_t)ints * sizeof(int));
    if (a)
        *pi = a;
    b = realloc(*pd, (size_t)ncap * (size_t)dbls * sizeof(double));
    if (b)
        *pd = b;
    if (!a || !b) {
        log->full = 1;
        return 0;
    }
    *cap = ncap;
    return 1;
}

void rt_trace_set_kind(const rt_scene *s, int kind)
{
    if (s->trace)
        s->trace->kind = kind;
}

void rt_trace_query(const rt_scene *s, const double o[3], const double d[3], double tmin, double tmax, int mode,
                    int skip)
{
    rt_trace_log *log = s->trace;
    int *qi;
    double *qd;
    if (!log || !room(log, log->nq, &log->capq, &log->qi, 3, &log->qd, 8))
        return;
    qi = log->qi + 3 * log->nq;
    qd = log->qd + 8 * log->nq++;
    qi[0] = log->kind;
    qi[1] = mode;
    qi[2] = skip;
    memcpy(qd, o, 3 * sizeof(double));
    memcpy(qd + 3, d, 3 * sizeof(double));
    qd[6] = tmin;
    qd[7] = tmax;
}

void rt_trace_solve(const rt_scene *s, int leaf, const double o[3], const double u[3], double lo, double hi, int mode,
                    int nr, const double *r)
{
    rt_trace_log *log = s->trace;
    double t0 = lo, t1 = hi;
    int *si, keep = nr, first = 0;
    double *sd;
    if (!log || (mode != RT_TRACE_PLANE && !ig_shape_clip(&s->nodes[leaf].prep, o, u, &t0, &t1)))
        return;                           /* the ray does not enter the leaf's box: no solve work */
    if (mode != IG_ALL_ROOTS && nr > 1) { /* a nearest-hit solve that fell back to all roots: its hit is one */
        while (first + 1 < nr && !(r[first] > lo))
            ++first;
        keep = 1;
    }
    if (!room(log, log->ns, &log->caps, &log->si, 4, &log->sd, 8))
        return;
    if (log->nr + keep > log->capr) {
        long ncap = log->capr ? 2 * log->capr : 4096;
        double *a = realloc(log->roots, (size_t)ncap * sizeof(double));
        if (!a) {
            log->full = 1;
            return;
        }
        log->roots = a;
        log->capr = ncap;
    }
    si = log->si + 4 * log->ns;
    sd = log->sd + 8 * log->ns++;
    si[0] = log->kind;
    si[1] = leaf;
    si[2] = mode;
    si[3] = keep;
    memcpy(sd, o, 3 * sizeof(double));
    memcpy(sd + 3, u, 3 * sizeof(double));
    sd[6] = t0;
    sd[7] = t1;
    memcpy(log->roots + log->nr, r + first, (size_t)keep * sizeof(double));
    log->nr += keep;
}
#endif
