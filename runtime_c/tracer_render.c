/* Camera, stratified supersampling and the threaded render loop.
 *
 * Threads take image rows from a shared counter (so uneven rows balance themselves) and write disjoint
 * parts of the output. Samples come from a per-pixel random stream seeded by (seed, pixel), so an image is
 * the same whatever the thread count, and a band of rows (rt_render_set_rows, a tile) is exactly those rows
 * of the whole image. The render context holds all mutable state; a mutex guards the row
 * counter, the progress count, the cancel flag and the ray statistics.
 */
#include "tracer_internal.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

struct rt_render {
    const rt_scene *s;
    int width, height, spp, max_depth, threads;
    int y0, y1; /* the rows rt_render_run renders: [y0, y1) of the image (all of it unless set) */
    unsigned long seed;
    float *rgb;
    /* camera frame */
    double eye[3], u[3], v[3], w[3], tan_half, aspect;
    /* shared, under lock */
    pthread_mutex_t lock;
    int next_row, rows_done, cancel;
    double stats[RT_NSTATS];
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

void rt_render_free(rt_render *r)
{
    if (!r)
        return;
    pthread_mutex_destroy(&r->lock);
    free(r);
}

static void render_row(rt_render *r, int y, double stats[RT_NSTATS], int *perm)
{
    int x, k, a;
    /* one sample per pixel: at the pixel's centre, the same for the whole row in y, and no random numbers */
    const double py_centre = (1.0 - 2.0 * (y + 0.5) / r->height) * r->tan_half;
    for (x = 0; x < r->width; ++x) {
        uint64_t rng = 0;
        double acc[3] = {0.0, 0.0, 0.0};
        if (r->spp > 1) {
            rng = (uint64_t)r->seed * 0x100000001B3ULL ^ ((uint64_t)y * (uint64_t)r->width + (uint64_t)x);
            splitmix64(&rng);
            /* N-rooks stratification: sample k sits in column stratum k and row stratum perm[k]. */
            for (k = 0; k < r->spp; ++k)
                perm[k] = k;
            for (k = r->spp - 1; k > 0; --k) {
                int j = (int)(splitmix64(&rng) % (uint64_t)(k + 1)), t = perm[k];
                perm[k] = perm[j];
                perm[j] = t;
            }
        }
        for (k = 0; k < r->spp; ++k) {
            double sx, sy, px, py, d[3], c[3];
            if (r->spp == 1) {
                px = (2.0 * (x + 0.5) / r->width - 1.0) * r->tan_half * r->aspect;
                py = py_centre;
            } else {
                sx = (k + uniform01(&rng)) / r->spp;
                sy = (perm[k] + uniform01(&rng)) / r->spp;
                px = (2.0 * (x + sx) / r->width - 1.0) * r->tan_half * r->aspect;
                py = (1.0 - 2.0 * (y + sy) / r->height) * r->tan_half;
            }
            for (a = 0; a < 3; ++a)
                d[a] = px * r->u[a] + py * r->v[a] - r->w[a];
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

static void *worker(void *arg)
{
    rt_render *r = arg;
    double stats[RT_NSTATS] = {0.0, 0.0, 0.0, 0.0};
    int *perm = malloc((size_t)r->spp * sizeof(int)), y, a;
    if (!perm)
        return NULL;
    for (;;) {
        pthread_mutex_lock(&r->lock);
        if (r->cancel || r->next_row >= r->y1) {
            pthread_mutex_unlock(&r->lock);
            break;
        }
        y = r->next_row++;
        pthread_mutex_unlock(&r->lock);
        render_row(r, y, stats, perm);
        pthread_mutex_lock(&r->lock);
        r->rows_done++;
        pthread_mutex_unlock(&r->lock);
    }
    pthread_mutex_lock(&r->lock);
    for (a = 0; a < RT_NSTATS; ++a)
        r->stats[a] += stats[a];
    pthread_mutex_unlock(&r->lock);
    free(perm);
    return NULL;
}

int rt_render_run(rt_render *r, float *rgb)
{
    pthread_t *ids;
    pthread_attr_t attr;
    int rows = r->y1 - r->y0, n = r->threads < rows ? r->threads : rows, started = 0, i, cancelled;
    r->rgb = rgb;
    pthread_mutex_lock(&r->lock);
    r->next_row = r->y0;
    r->rows_done = 0;
    pthread_mutex_unlock(&r->lock);
    memset(rgb, 0, (size_t)r->width * (size_t)rows * 3 * sizeof(float));
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
    pthread_mutex_unlock(&r->lock);
    return cancelled ? 1 : 0;
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
