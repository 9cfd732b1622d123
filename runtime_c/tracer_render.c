/* Camera, stratified supersampling and the threaded render loop.
 *
 * Threads take image rows from a shared counter (so uneven rows balance themselves) and write disjoint
 * parts of the output. Samples come from a per-pixel random stream seeded by (seed, pixel), so an image is
 * the same whatever the thread count, and a band of rows (rt_render_set_rows, a tile) is exactly those rows
 * of the whole image. The render context holds all mutable state; a mutex guards the row
 * counter, the progress count, the cancel flag and the ray statistics.
 *
 * What the threads share is kept off their hot path: each thread counts its rays in its own stack frame and
 * adds them to the context once, at its end; one lock per row both reports the row done and claims the
 * next; the mutable fields sit on cache lines of their own, away from the camera frame every pixel reads;
 * and each thread writes the first touch of its own rows (no serial clearing of the image before the
 * threads start: only rows a cancelled render never reached are cleared, after it).
 *
 * A render may also be made in passes (rt_render_set_pass), as a viewer refines its picture: each pass adds
 * samples [k0, k1) of every pixel, the very samples a whole render takes, to running sums in double kept by
 * the caller, in the same order, so that after the last pass (k1 = spp) the image is the whole render's bit for
 * bit. A pass may take only the pixels whose x and y are both even (a quarter of them: a half-size picture
 * first) or only the others.
 */
#if defined(__linux__) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* sched_getaffinity, sched_setaffinity: one thread per core when all cores render */
#endif
#include "certify.h"
#include "tracer_internal.h"

#include <math.h>
#include <pthread.h>
#ifdef __linux__
#include <sched.h>
#endif
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

struct rt_render {
    const rt_scene *s;
    int width, height, spp, max_depth, threads;
    int y0, y1;   /* the rows rt_render_run renders: [y0, y1) of the image (all of it unless set) */
    int k0, k1;   /* the samples of each pixel rt_render_run adds: [k0, k1) of spp (all of them unless set) */
    int pixels;   /* which pixels it renders: RT_PIXELS_ALL, RT_PIXELS_EVEN or RT_PIXELS_ODD */
    double *sums; /* a pass's running sums, 3 a pixel of rows [y0, y1); NULL for a whole render */
    unsigned long seed;
    float *rgb;
    /* camera frame */
    double eye[3], u[3], v[3], w[3], tan_half, aspect;
    /* shared, under lock, apart from the read-only fields above (which every pixel reads): a line written
     * by one thread is invalidated in the other's cache */
    char pad_before[64];
    pthread_mutex_t lock;
    int next_row, rows_done, cancel;
    int pin, pinned; /* pin: each worker keeps itself on its own allowed core; pinned: workers numbered so far */
    double stats[RT_NSTATS];
    char pad_after[64];
};

static uint64_t splitmix64(uint64_t *x)
{
    uint64_t z = (*x += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static double uniform01(uint64_t *x) { return (double)(splitmix64(x) >> 11) * (1.0 / 9007199254740992.0); }

static void cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static int unit3(double v[3])
{
    double l = sqrt(rt_dot(v, v));
    if (!(l > 0.0) || !isfinite(l))
        return 0;
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
    return 1;
}

rt_render *rt_render_new(const rt_scene *s, int width, int height, int spp, int max_depth, int threads,
                         unsigned long seed)
{
    rt_render *r;
    int a;
    if (!s || !s->committed || width <= 0 || height <= 0 || spp <= 0 || spp > RT_MAX_SPP)
        return NULL;
    r = calloc(1, sizeof *r);
    if (!r)
        return NULL;
    r->s = s;
    r->width = width;
    r->height = height;
    r->y0 = 0;
    r->y1 = height;
    r->k0 = 0;
    r->k1 = spp;
    r->pixels = RT_PIXELS_ALL;
    r->spp = spp;
    r->max_depth = max_depth < 0 ? 0 : (max_depth > RT_MAX_DEPTH ? RT_MAX_DEPTH : max_depth);
    r->threads = threads < 1 ? 1 : threads;
    r->seed = seed;
    memcpy(r->eye, s->eye, sizeof r->eye);
    for (a = 0; a < 3; ++a)
        r->w[a] = s->eye[a] - s->look_at[a];
    if (!unit3(r->w))
        r->w[2] = 1.0;
    cross3(s->up, r->w, r->u);
    if (!unit3(r->u)) { /* up parallel to the view direction: pick any perpendicular */
        double alt[3] = {1.0, 0.0, 0.0};
        if (fabs(r->w[0]) > 0.9)
            alt[0] = 0.0, alt[1] = 1.0;
        cross3(alt, r->w, r->u);
        unit3(r->u);
    }
    cross3(r->w, r->u, r->v);
    r->tan_half = tan(0.5 * s->vfov * 3.14159265358979323846 / 180.0);
    r->aspect = (double)width / (double)height;
    if (pthread_mutex_init(&r->lock, NULL) != 0) {
        free(r);
        return NULL;
    }
    return r;
}

int rt_render_set_rows(rt_render *r, int y0, int y1)
{
    if (!r || y0 < 0 || y1 > r->height || y0 >= y1)
        return -1;
    pthread_mutex_lock(&r->lock);
    r->y0 = y0;
    r->y1 = y1;
    pthread_mutex_unlock(&r->lock);
    return 0;
}

int rt_render_set_pass(rt_render *r, int k0, int k1, int pixels, double *sums)
{
    if (!r || k0 < 0 || k1 > r->spp || k0 >= k1 || pixels < RT_PIXELS_ALL || pixels > RT_PIXELS_ODD || !sums)
        return -1;
    pthread_mutex_lock(&r->lock);
    r->k0 = k0;
    r->k1 = k1;
    r->pixels = pixels;
    r->sums = sums;
    pthread_mutex_unlock(&r->lock);
    return 0;
}

void rt_render_free(rt_render *r)
{
    if (!r)
        return;
    pthread_mutex_destroy(&r->lock);
    free(r);
}

/* The pixel's random stream, after the stratification's permutation (perm) is drawn from it, as render_row
 * draws them: sample k's two numbers are the stream's next two once samples 0 .. k-1 have taken theirs. */
static uint64_t pixel_stream(const rt_render *r, int x, int y, int *perm)
{
    uint64_t rng = (uint64_t)r->seed * 0x100000001B3ULL ^ ((uint64_t)y * (uint64_t)r->width + (uint64_t)x);
    int k;
    splitmix64(&rng);
    /* N-rooks stratification: sample k sits in column stratum k and row stratum perm[k]. */
    for (k = 0; k < r->spp; ++k)
        perm[k] = k;
    for (k = r->spp - 1; k > 0; --k) {
        int j = (int)(splitmix64(&rng) % (uint64_t)(k + 1)), t = perm[k];
        perm[k] = perm[j];
        perm[j] = t;
    }
    return rng;
}

/* Sample k's primary direction through pixel (x, y): the pixel's centre at one sample a pixel (no random
 * numbers), else its N-rooks stratum jittered by two numbers drawn from the pixel's stream. */
static void sample_dir(const rt_render *r, int x, int y, int k, uint64_t *rng, const int *perm, double d[3])
{
    double px, py;
    int a;
    if (r->spp == 1) {
        px = (2.0 * (x + 0.5) / r->width - 1.0) * r->tan_half * r->aspect;
        py = (1.0 - 2.0 * (y + 0.5) / r->height) * r->tan_half;
    } else {
        const double sx = (k + uniform01(rng)) / r->spp;
        const double sy = (perm[k] + uniform01(rng)) / r->spp;
        px = (2.0 * (x + sx) / r->width - 1.0) * r->tan_half * r->aspect;
        py = (1.0 - 2.0 * (y + sy) / r->height) * r->tan_half;
    }
    for (a = 0; a < 3; ++a)
        d[a] = px * r->u[a] + py * r->v[a] - r->w[a];
}

/* A pass's row (rt_render_set_pass): its pixels' samples [k0, k1) added to their sums. The samples are
 * render_row's, drawn from the same stream in the same order (a test holds the two to the same image). */
static void render_row_pass(rt_render *r, int y, double stats[RT_NSTATS], int *perm)
{
    int x, k, a, x0 = 0, step = 1;
    if (r->pixels != RT_PIXELS_ALL && y % 2 == 0) { /* even pixels: even x of an even row; the others: odd x */
        x0 = r->pixels == RT_PIXELS_ODD;
        step = 2;
    } else if (r->pixels == RT_PIXELS_EVEN) {
        return; /* an odd row has no even pixel */
    }
    for (x = x0; x < r->width; x += step) {
        const size_t at = ((size_t)(y - r->y0) * (size_t)r->width + (size_t)x) * 3;
        uint64_t rng = r->spp > 1 ? pixel_stream(r, x, y, perm) : 0;
        double acc[3] = {0.0, 0.0, 0.0};
        for (k = 0; k < r->k0; ++k) { /* a later pass: the samples before k0 are in the sums */
            splitmix64(&rng);
            splitmix64(&rng);
        }
        if (r->k0 > 0)
            memcpy(acc, r->sums + at, sizeof acc);
        for (k = r->k0; k < r->k1; ++k) {
            double d[3], c[3];
            sample_dir(r, x, y, k, &rng, perm, d);
            rt_trace_ray(r->s, r->eye, d, r->max_depth, c, stats);
            if (!isfinite(c[0]) || !isfinite(c[1]) || !isfinite(c[2])) {
                stats[RT_NONFINITE] += 1.0;
                continue;
            }
            for (a = 0; a < 3; ++a)
                acc[a] += c[a];
        }
        for (a = 0; a < 3; ++a) {
            double v = acc[a] / r->k1;
            r->rgb[at + (size_t)a] = (float)v;
        }
        memcpy(r->sums + at, acc, sizeof acc);
    }
}

static void render_row(rt_render *r, int y, double stats[RT_NSTATS], int *perm)
{
    int x, k, a;
    for (x = 0; x < r->width; ++x) {
        uint64_t rng = r->spp > 1 ? pixel_stream(r, x, y, perm) : 0;
        double acc[3] = {0.0, 0.0, 0.0};
        for (k = 0; k < r->spp; ++k) {
            double d[3], c[3];
            sample_dir(r, x, y, k, &rng, perm, d);
            rt_trace_ray(r->s, r->eye, d, r->max_depth, c, stats);
            if (!isfinite(c[0]) || !isfinite(c[1]) || !isfinite(c[2])) {
                stats[RT_NONFINITE] += 1.0;
                continue;
            }
            for (a = 0; a < 3; ++a)
                acc[a] += c[a];
        }
        for (a = 0; a < 3; ++a) {
            double v = acc[a] / r->spp;
            r->rgb[((size_t)(y - r->y0) * (size_t)r->width + (size_t)x) * 3 + (size_t)a] = (float)v;
        }
    }
}

/* When a render uses exactly the cores it may run on, worker k keeps itself on the k-th of them. Rows are
 * handed out dynamically, so a core another process keeps busy only gives its thread fewer rows; but a
 * scheduler that packs new threads onto the cores already running (some virtual machines' kernels do, for
 * tens of milliseconds) can no longer run a short render's threads one after the other on one core.
 * Each worker pins itself, while it runs: pinning a worker from outside after it has finished (a tiny render)
 * reaches a thread the kernel no longer has, and glibc then pins the calling thread instead, so every later
 * render from that thread would inherit one core. */
static int pinning_wanted(int n)
{
#ifdef __linux__
    cpu_set_t allowed;
    return n >= 2 && sched_getaffinity(0, sizeof allowed, &allowed) == 0 && CPU_COUNT(&allowed) == n;
#else
    (void)n;
    return 0;
#endif
}

/* Keep the calling thread on the k-th core of those it may run on (a new thread inherits its creator's). */
static void pin_self(int k)
{
#ifdef __linux__
    cpu_set_t allowed, one;
    int cpu;
    if (sched_getaffinity(0, sizeof allowed, &allowed) != 0)
        return;
    for (cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
        if (!CPU_ISSET(cpu, &allowed) || k-- > 0)
            continue;
        CPU_ZERO(&one);
        CPU_SET(cpu, &one);
        sched_setaffinity(0, sizeof one, &one); /* a failure leaves the thread where it was */
        return;
    }
#else
    (void)k;
#endif
}

static void *worker(void *arg)
{
    rt_render *r = arg;
    double stats[RT_NSTATS] = {0.0, 0.0, 0.0, 0.0};
    int *perm = malloc((size_t)r->spp * sizeof(int)), y = -1, a;
    if (!perm)
        return NULL;
    if (r->pin) {
        pthread_mutex_lock(&r->lock);
        a = r->pinned++;
        pthread_mutex_unlock(&r->lock);
        pin_self(a);
    }
    for (;;) {
        pthread_mutex_lock(&r->lock); /* one lock per row: the row done, and the next one claimed */
        if (y >= 0)
            r->rows_done++;
        if (r->cancel || r->next_row >= r->y1) {
            for (a = 0; a < RT_NSTATS; ++a)
                r->stats[a] += stats[a];
            pthread_mutex_unlock(&r->lock);
            break;
        }
        y = r->next_row++;
        pthread_mutex_unlock(&r->lock);
        if (r->sums)
            render_row_pass(r, y, stats, perm);
        else
            render_row(r, y, stats, perm);
    }
    free(perm);
    return NULL;
}

int rt_render_run(rt_render *r, float *rgb)
{
    pthread_t *ids;
    pthread_attr_t attr;
    int rows = r->y1 - r->y0, n = r->threads < rows ? r->threads : rows, started = 0, i, cancelled, reached;
    const size_t row_floats = (size_t)r->width * 3;
    r->rgb = rgb;
    pthread_mutex_lock(&r->lock);
    r->next_row = r->y0;
    r->rows_done = 0;
    r->pin = pinning_wanted(n);
    r->pinned = 0;
    pthread_mutex_unlock(&r->lock);
    ids = malloc((size_t)n * sizeof *ids);
    if (!ids)
        return -1;
    /* CSG recursion keeps span lists on the stack: ask for a generous stack. */
    pthread_attr_init(&attr);
    pthread_attr_setstacksize(&attr, (size_t)16 << 20);
    for (i = 0; i < n; ++i)
        if (pthread_create(&ids[started], &attr, worker, r) == 0)
            ++started;
    pthread_attr_destroy(&attr);
    if (started == 0) {
        free(ids);
        return -1;
    }
    for (i = 0; i < started; ++i)
        pthread_join(ids[i], NULL);
    free(ids);
    pthread_mutex_lock(&r->lock);
    cancelled = r->cancel && r->rows_done < rows;
    reached = r->next_row; /* every row claimed was finished: a thread checks cancel only between rows */
    pthread_mutex_unlock(&r->lock);
    if (reached < r->y1) /* cancelled, or no thread could get its scratch memory: those rows are black */
        memset(rgb + (size_t)(reached - r->y0) * row_floats, 0, (size_t)(r->y1 - reached) * row_floats * sizeof(float));
    return cancelled ? 1 : (reached < r->y1 ? -1 : 0);
}

int rt_render_progress(rt_render *r)
{
    int v;
    pthread_mutex_lock(&r->lock);
    v = r->rows_done;
    pthread_mutex_unlock(&r->lock);
    return v;
}

void rt_render_cancel(rt_render *r)
{
    pthread_mutex_lock(&r->lock);
    r->cancel = 1;
    pthread_mutex_unlock(&r->lock);
}

void rt_render_stats(rt_render *r, double out[RT_NSTATS])
{
    pthread_mutex_lock(&r->lock);
    memcpy(out, r->stats, sizeof r->stats);
    pthread_mutex_unlock(&r->lock);
}

/* ---- for the certify pass (certify.c): the primary rays exactly as render_row makes them ---- */

const rt_scene *rt_render_scene(const rt_render *r) { return r->s; }

void rt_render_shape(const rt_render *r, int *y0, int *y1, int *width, int *spp, int *threads)
{
    *y0 = r->y0;
    *y1 = r->y1;
    *width = r->width;
    *spp = r->spp;
    *threads = r->threads;
}

int rt_render_primary_rays(const rt_render *r, int x, int y, double o[3], double *dirs)
{
    int k, *perm = NULL, stack_perm[64];
    uint64_t rng = 0;
    memcpy(o, r->eye, sizeof r->eye);
    if (r->spp > 1) {
        perm = r->spp <= 64 ? stack_perm : malloc((size_t)r->spp * sizeof(int));
        if (!perm)
            return 0;
        rng = pixel_stream(r, x, y, perm);
    }
    for (k = 0; k < r->spp; ++k)
        sample_dir(r, x, y, k, &rng, perm, dirs + 3 * k);
    if (perm && perm != stack_perm)
        free(perm);
    return r->spp;
}
