/* Certified primary rays (certify.h; what a certificate is: docs/certify.md).
 *
 * For each object the ray is taken into the object's space as balls (the exact inverse of the object's map is
 * within a bound of the computed one), the range of t inside the object's box is worked out with a band for the
 * rounding of its ends, the coefficients of f along the ray come with their error bounds (the shape's
 * coeffs_err), and certify_poly.c proves the first root on the range or that there is none. The objects'
 * answers are then ordered: the first hit must be apart from every other object's, and the tracer's own answer
 * (rt_scene_closest) must be the certified one.
 */
#include "certify.h"
#include "errarith.h"
#include "tracer_internal.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#define HINT_REL 1e-9  /* the tracer's root is checked in an interval of this relative half-width */
#define HINT_WIDE 1e-3 /* ... and, expanded about that root, in one of this relative half-width */
#define CERT_REL 1e-7  /* a hit's interval is narrowed to this relative width (where the pieces tell) */
#define GAMMA(k) ((double)(k)*1.0000001 * IG_ERR_U) /* gamma_k = k u / (1 - k u), rounded up */

static const char *const reason_names[RT_CERT_NCODES] = {
    "miss", "hit", "tangent", "singular", "noise", "tie", "overflow", "budget", "no_bound", "far", "wrong",
};

const char *rt_certify_reason(int code) { return code >= 0 && code < RT_CERT_NCODES ? reason_names[code] : NULL; }

/* One object's answer: code (MISS, HIT or a reason), the hit's t-interval, where a failure starts. */
typedef struct {
    int code;
    double lo, hi; /* HIT: the first root's interval; a failure: lo = where the undecided part starts */
} obj_cert;

/* A ray in a leaf's object space as balls: |O - oo| <= eo, |D - od| <= ed componentwise, for the exact object-space
 * ray O + t D of the world ray (the same t). 0 when the map's inverse cannot be bounded. */
typedef struct {
    double oo[3], eo[3], od[3], ed[3];
} ball_ray;

/* A bound delta with |M^-1 - minv| <= delta entrywise (as a max-row-sum bound): minv M = I + R gives
 * M^-1 - minv = -(I + R)^-1 R minv. */
static double inverse_bound(const rt_node *n)
{
    double rn = 0.0, mn = 0.0;
    int i, j, k;
    for (i = 0; i < 3; ++i) {
        double rrow = 0.0, mrow = 0.0;
        for (j = 0; j < 3; ++j) {
            double v = i == j ? -1.0 : 0.0, a = 0.0;
            for (k = 0; k < 3; ++k) {
                v += n->minv[4 * i + k] * n->m[4 * k + j];
                a += fabs(n->minv[4 * i + k] * n->m[4 * k + j]);
            }
            rrow += fabs(v) + GAMMA(5) * (a + 1.0);
            mrow += fabs(n->minv[4 * i + j]);
        }
        rn = ig_max(rn, rrow);
        mn = ig_max(mn, mrow);
    }
    rn *= 1.0 + GAMMA(4);
    if (!(rn < 0.5))
        return INFINITY;
    return rn * mn / (1.0 - rn) * (1.0 + GAMMA(8));
}

static int ball_ray_of(const rt_node *n, const double o[3], const double d[3], ball_ray *br)
{
    double w[3], wn = 0.0, dn = 0.0, delta;
    int i, j;
    if (n->identity) {
        for (i = 0; i < 3; ++i) {
            br->oo[i] = o[i];
            br->od[i] = d[i];
            br->eo[i] = br->ed[i] = 0.0;
        }
        return 1;
    }
    delta = inverse_bound(n);
    if (!isfinite(delta))
        return 0;
    for (i = 0; i < 3; ++i) {
        w[i] = o[i] - n->m[4 * i + 3];
        wn = ig_max(wn, fabs(w[i]) * (1.0 + IG_ERR_U));
        dn = ig_max(dn, fabs(d[i]));
    }
    for (i = 0; i < 3; ++i) {
        double so = 0.0, sd = 0.0, ao = 0.0, ad = 0.0, aw = 0.0;
        for (j = 0; j < 3; ++j) {
            double mij = n->minv[4 * i + j];
            so += mij * w[j];
            sd += mij * d[j];
            ao += fabs(mij * w[j]);
            ad += fabs(mij * d[j]);
            aw += fabs(mij) * IG_ERR_U * fabs(w[j]); /* the rounding of w */
        }
        br->oo[i] = so;
        br->od[i] = sd;
        br->eo[i] = (GAMMA(4) * ao + aw * (1.0 + GAMMA(4)) + delta * wn) * (1.0 + GAMMA(4)) + IG_ERR_ETA;
        br->ed[i] = (GAMMA(4) * ad + delta * dn) * (1.0 + GAMMA(4)) + IG_ERR_ETA;
    }
    return 1;
}

/* The exact ray's range in the (grown) box, [*t0, *t1] from t = 0, and a band such that the exact ends are within
 * it of these. Returns 0: the box is certainly missed; 1: a range; -1: undecided (a direction parallel to a
 * face within its error). */
static int box_range(const rt_node *n, const ball_ray *br, double *t0, double *t1, double *band)
{
    double lo = 0.0, hi = INFINITY, slack = 0.0;
    int a;
    for (a = 0; a < 3; ++a) {
        double bl = n->prep.lo[a], bh = n->prep.hi[a], ta, tb, d = br->od[a];
        if (!n->prep.bounded || (!isfinite(bl) && !isfinite(bh)))
            continue;
        if (!(fabs(d) > br->ed[a])) {
            if (br->ed[a] > 0.0 || br->eo[a] > 0.0)
                return -1;
            if (!(br->oo[a] >= bl && br->oo[a] <= bh))
                return 0;
            continue;
        }
        ig_slab(bl, bh, br->oo[a], 1.0 / d, &ta, &tb);
        {
            double tm = ig_max(isfinite(ta) ? fabs(ta) : 0.0, isfinite(tb) ? fabs(tb) : 0.0);
            slack =
                ig_max(slack, (br->eo[a] + tm * br->ed[a]) / (fabs(d) - br->ed[a]) * (1.0 + GAMMA(4)) + GAMMA(4) * tm);
        }
        if (ta > lo)
            lo = ta;
        if (tb < hi)
            hi = tb;
    }
    *t0 = lo;
    *t1 = hi;
    *band = slack + IG_ERR_ETA;
    if (!(lo <= hi + 2.0 * *band))
        return 0;
    return 1;
}

/* Coefficient balls of f along the exact ray about t = ts: f(O + (ts + s) D) = sum c_k s^k. */
static int shifted_coeffs(const rt_node *n, const ball_ray *br, double ts, double *c, double *e)
{
    double os[3], eos[3];
    int a, k;
    for (a = 0; a < 3; ++a) {
        double p = ts * br->od[a];
        os[a] = br->oo[a] + p;
        eos[a] = (br->eo[a] + fabs(ts) * br->ed[a] + IG_ERR_U * (fabs(p) + fabs(os[a]))) * (1.0 + GAMMA(4));
    }
    if (!n->shape->coeffs_err(os, eos, br->od, br->ed, n->params, c, e))
        return 0;
    for (k = 0; k <= n->shape->degree; ++k)
        if (!isfinite(c[k]) || !isfinite(e[k]))
            return -1;
    return 1;
}

/* Is the point of the ray at t (object space) near a singular point of f: grad f within 1e4 times its own error
 * bound (the coefficients along the three axes: their c_1 is a partial derivative)? A label only. */
static int near_singular(const rt_node *n, const ball_ray *br, double t)
{
    double p[3], zero[3] = {0.0, 0.0, 0.0}, c[IG_MAX_DEGREE + 1], e[IG_MAX_DEGREE + 1], g2 = 0.0, em = 0.0;
    int a;
    for (a = 0; a < 3; ++a)
        p[a] = br->oo[a] + t * br->od[a];
    for (a = 0; a < 3; ++a) {
        double u[3] = {0.0, 0.0, 0.0};
        u[a] = 1.0;
        if (!n->shape->coeffs_err(p, zero, u, zero, n->params, c, e) || n->shape->degree < 1)
            return 0;
        g2 += c[1] * c[1];
        em = ig_max(em, e[1] + IG_ERR_U * fabs(c[0]));
    }
    return sqrt(g2) <= 1e4 * em;
}

/* Cauchy's bound on the roots' size, from the balls: every root s has |s| < 1 + max |c_k| / |c_n|. INFINITY when
 * the leading ball holds zero. */
static double cauchy_bound(const double *c, const double *e, int n)
{
    double lead = fabs(c[n]) - e[n], m = 0.0;
    int k;
    if (!(lead > 0.0))
        return INFINITY;
    for (k = 0; k < n; ++k)
        m = ig_max(m, (fabs(c[k]) + e[k]) / lead);
    return (1.0 + m) * (1.0 + GAMMA(4));
}

static inline double min3(double a, double b, double c)
{
    double m = a < b ? a : b;
    return m < c ? m : c;
}

/* The first root on [ta, tb] (in t) of the expansion about ts: certify_poly's answer, the interval in t. */
static int first_root_t(const double *c, const double *e, int deg, double ts, double ta, double tb, double *lo,
                        double *hi)
{
    double sa = ta - ts, sb = tb - ts;
    int got;
    sa -= 2.0 * IG_ERR_U * fabs(sa) + IG_ERR_ETA;
    sb += 2.0 * IG_ERR_U * fabs(sb) + IG_ERR_ETA;
    got = rt_certify_first_root(c, e, deg, sa, sb, ts, CERT_REL, lo, hi);
    *lo = ts + *lo;
    *hi = ts + *hi;
    *lo -= 2.0 * IG_ERR_U * fabs(*lo) + IG_ERR_ETA;
    *hi += 2.0 * IG_ERR_U * fabs(*hi) + IG_ERR_ETA;
    return got;
}

/* The first root on [ta, tb] proved near the tracer's own root `hint` (what the plain render found; INFINITY
 * for none): no root on [ta, hint - w], and the first root of [hint - w, hint + w] isolated, w = HINT_REL |hint|.
 * 1 and the interval; -1 when the hint does not lead to a proof (the caller then walks [ta, tb] whole). */
static int hinted_root(const double *c, const double *e, int deg, double ts, double ta, double tb, double hint,
                       double *lo, double *hi)
{
    double w = HINT_REL * fabs(hint) + 1e-300, l, h;
    if (!(hint - w > ta && hint + w < tb))
        return -1;
    if (first_root_t(c, e, deg, ts, ta, hint - w, &l, &h) != 0)
        return -1;
    if (first_root_t(c, e, deg, ts, hint - w, hint + w, lo, hi) != 1)
        return -1;
    return 1;
}

/* The same with f expanded again about the tracer's root: where the expansion about ts sees f near its root only
 * through the noise of terms far larger than f there (a surface of high degree seen through its box's centre),
 * the expansion about the root does not. No root on [ta, hint - W] from the first expansion, then the first root
 * of [hint - W, hint + W] from the second, W = HINT_WIDE |hint| (cut to [ta, tb]). */
static int reexpanded_root(const rt_node *n, const ball_ray *br, const double *c, const double *e, double ts, double ta,
                           double tb, double hint, double *lo, double *hi)
{
    double c2[IG_MAX_DEGREE + 1], e2[IG_MAX_DEGREE + 1], W = HINT_WIDE * fabs(hint), a, b, l, h;
    int deg = n->shape->degree;
    if (!(hint > ta && hint < tb) || shifted_coeffs(n, br, hint, c2, e2) <= 0)
        return -1;
    a = ig_max(ta, hint - W);
    b = hint + W < tb ? hint + W : tb;
    if (a > ta && first_root_t(c, e, deg, ts, ta, a, &l, &h) != 0)
        return -1;
    return first_root_t(c2, e2, deg, hint, a, b, lo, hi) == 1 ? 1 : -1;
}

static int set_fail(obj_cert *out, int code, double at)
{
    out->code = code;
    out->lo = at;
    out->hi = INFINITY;
    return 0;
}

/* The leaf's range, its expansion and its certificate: the exact range starts in [A, S1] and ends in [M, T]
 * (the box's faces, rounded; S1 = A and M = T where an end is exact); the first root must lie in [S1, M] with
 * no root in [A, S1], or there is none in [A, T]. */
static int leaf_range_cert(const rt_node *n, const ball_ray *br, double A, double S1, double M, double T, double far_t,
                           double hint, obj_cert *out)
{
    double c[IG_MAX_DEGREE + 1], e[IG_MAX_DEGREE + 1], lo, hi;
    /* expanded about the tracer's root when there is one in range (f is smallest there, and so is its noise),
     * else about shape.c's shift point */
    double ts = hint > A && hint < T ? hint : ig_shape_shift_point(&n->prep, br->oo, br->od, A, T);
    int deg = n->shape->degree, got, k = shifted_coeffs(n, br, ts, c, e);
    if (k <= 0)
        return set_fail(out, k == 0 ? RT_CERT_NOBOUND : RT_CERT_OVERFLOW, A);
    if (S1 > A && first_root_t(c, e, deg, ts, A, S1, &lo, &hi) != 0)
        return set_fail(out, RT_CERT_NOISE, A); /* a root near where the range starts */
    got = hinted_root(c, e, deg, ts, S1, M, hint, &lo, &hi);
    if (got < 0)
        got = reexpanded_root(n, br, c, e, ts, S1, M, hint, &lo, &hi);
    if (got < 0)
        got = first_root_t(c, e, deg, ts, S1, M, &lo, &hi);
    if (got < 0) {
        k = -got;
        if (k == RT_CERT_TANGENT && near_singular(n, br, 0.5 * (lo + hi)))
            k = RT_CERT_SINGULAR;
        return set_fail(out, k, lo);
    }
    if (got == 1) {
        /* the interval, rounded outward, may reach past S1 .. M by a rounding: before t = 0, or into the band where
         * the exact range may already have ended, the root is not known to be in range */
        if (lo <= 0.0 || (hi > M && M < T))
            return set_fail(out, RT_CERT_NOISE, lo);
        if (hi >= far_t * (1.0 - 1e-12))
            return set_fail(out, RT_CERT_FAR, lo);
        out->code = RT_CERT_HIT;
        out->lo = lo;
        out->hi = hi;
        return 1;
    }
    if (T > M && first_root_t(c, e, deg, ts, M, T, &lo, &hi) != 0)
        return set_fail(out, RT_CERT_NOISE, M); /* a root near where the range ends */
    /* no root on the range: for an unbounded object cut at far, none beyond it either */
    if (T >= far_t && !(ts + cauchy_bound(c, e, deg) < far_t))
        return set_fail(out, RT_CERT_FAR, T);
    return 0;
}

/* A top-level leaf's first hit along the exact ray for t in (0, cap] (the cap: the best hit so far; a root beyond
 * it does not matter). */
static int leaf_cert(const rt_node *n, const rt_ray *ray, double cap, double hint, obj_cert *out)
{
    ball_ray br;
    double t0, t1, band, far_t = n->wbounded ? INFINITY : ray->far_t, A, S1, M, T;
    int got;
    out->code = RT_CERT_MISS;
    out->lo = out->hi = INFINITY;
    if (n->clip != RT_CLIP_NONE || !n->shape->coeffs_err || n->prep.degree < 0 || !ball_ray_of(n, ray->o, ray->d, &br))
        return set_fail(out, RT_CERT_NOBOUND, 0.0);
    got = box_range(n, &br, &t0, &t1, &band);
    if (got <= 0)
        return got < 0 ? set_fail(out, RT_CERT_NOISE, 0.0) : 0;
    A = ig_max(0.0, t0 - band);
    S1 = ig_max(0.0, t0 + band);
    T = min3(t1 + band, ig_max(cap, 0.0), far_t);
    M = ig_max(S1, min3(t1 - band, cap, far_t));
    if (!(A <= T))
        return 0;
    if (M > T)
        M = T;
    return leaf_range_cert(n, &br, A, S1, M, T, far_t, hint, out);
}

/* Object k's answer for t in (0, cap]. */
static void object_cert(const rt_scene *s, int k, const rt_ray *ray, double cap, double hint, obj_cert *out)
{
    const rt_node *n = &s->nodes[s->objects[k]];
    double t0 = 0.0, t1 = cap;
    if (n->wbounded && !rt_clip_slabs(n->wbox, ray->o, ray->d, ray->inv, &t0, &t1, NULL, NULL)) {
        out->code = RT_CERT_MISS; /* the world box holds the object's box with a margin of 1e-9 of its size */
        out->lo = out->hi = INFINITY;
        return;
    }
    if (n->kind != RT_LEAF) {
        out->code = RT_CERT_NOBOUND; /* CSG objects are not certified (docs/certify.md) */
        out->lo = 0.0;
        out->hi = INFINITY;
        return;
    }
    (void)leaf_cert(n, ray, cap, hint, out);
}

/* The answers so far: the first hit W (the smallest interval start, lo1 .. hi1), the second smallest start, the
 * earliest failure. */
typedef struct {
    double cap, lo1, hi1, lo2, fail_at;
    int best, fail, fail_code;
} ray_answers;

static void take(ray_answers *q, int i, const obj_cert *c)
{
    if (c->code == RT_CERT_HIT) {
        if (c->lo < q->lo1) {
            q->lo2 = q->lo1;
            q->lo1 = c->lo;
            q->hi1 = c->hi;
            q->best = i;
        } else if (c->lo < q->lo2) {
            q->lo2 = c->lo;
        }
        if (c->hi < q->cap)
            q->cap = c->hi;
    } else if (c->code != RT_CERT_MISS && c->lo < q->fail_at) {
        q->fail_at = c->lo;
        q->fail = i;
        q->fail_code = c->code;
    }
}

/* The certified first hit over all objects: code, and the object in *object. The first hit W (the smallest
 * interval start) is certified when every other hit starts after W's interval ends and no object's certificate
 * failed before that end. The object the tracer shows (shown, at t_shown; -1: none) goes first, its certificate
 * starting at the tracer's root; every other object is then asked only up to the smallest interval end so far. */
static int scene_cert(const rt_scene *s, const rt_ray *ray, int shown, double t_shown, int *object)
{
    ray_answers q = {INFINITY, INFINITY, INFINITY, INFINITY, INFINITY, -1, -1, RT_CERT_MISS};
    obj_cert c;
    int i;
    if (shown >= 0) {
        object_cert(s, shown, ray, INFINITY, t_shown, &c);
        take(&q, shown, &c);
    }
    for (i = 0; i < s->nobjects; ++i) {
        if (i == shown)
            continue;
        object_cert(s, i, ray, q.cap, INFINITY, &c);
        take(&q, i, &c);
    }
    if (q.fail >= 0 && !(q.fail_at > q.hi1)) {
        *object = q.fail;
        return q.fail_code;
    }
    *object = q.best;
    if (q.best >= 0 && !(q.lo2 > q.hi1))
        return RT_CERT_TIE;
    return q.best >= 0 ? RT_CERT_HIT : RT_CERT_MISS;
}

int rt_certify_ray(const rt_scene *s, const double o[3], const double d[3], int *object)
{
    rt_ray ray;
    rt_pending ph;
    int code, shown;
    *object = -1;
    if (!s->committed)
        return RT_CERT_NOBOUND;
    rt_ray_init(&ray, o, d, s->far, s->unit_rays);
    shown = rt_scene_closest(s, o, d, 0.0, INFINITY, RT_CLOSEST, -1, &ph) ? ph.object : -1;
    code = scene_cert(s, &ray, shown, shown >= 0 ? ph.t : INFINITY, object);
    if ((code == RT_CERT_HIT || code == RT_CERT_MISS) && shown != *object) {
        *object = shown >= 0 ? shown : *object;
        return RT_CERT_WRONG;
    }
    return code;
}

/* ------------------------------------------------------------------ the certify pass of a render */

typedef struct {
    rt_render *r;
    unsigned char *map;
    int *objects;
    int y0, y1, width, spp;
    pthread_mutex_t lock;
    int next;
} cert_job;

/* One pixel: every sample certified with the same answer, or the first failing sample's code. */
static int pixel_code(const rt_scene *s, const rt_render *r, int x, int y, double *dirs, int *object)
{
    double o[3];
    int n = rt_render_primary_rays(r, x, y, o, dirs), k, code = RT_CERT_MISS, obj = -1;
    for (k = 0; k < n; ++k) {
        int ko, kc = rt_certify_ray(s, o, dirs + 3 * k, &ko);
        if (kc > RT_CERT_HIT) {
            *object = ko;
            return kc;
        }
        if (k == 0 || (code == RT_CERT_MISS && kc == RT_CERT_HIT)) { /* certified: the first hit sample names it */
            code = kc;
            obj = ko;
        }
    }
    *object = obj;
    return code;
}

static void *cert_worker(void *arg)
{
    cert_job *job = arg;
    const rt_scene *s = rt_render_scene(job->r);
    double *dirs = malloc((size_t)job->spp * 3 * sizeof(double));
    if (!dirs)
        return NULL;
    for (;;) {
        int y, x;
        pthread_mutex_lock(&job->lock);
        y = job->next++;
        pthread_mutex_unlock(&job->lock);
        if (y >= job->y1)
            break;
        for (x = 0; x < job->width; ++x) {
            size_t at = (size_t)(y - job->y0) * (size_t)job->width + (size_t)x;
            int obj;
            job->map[at] = (unsigned char)pixel_code(s, job->r, x, y, dirs, &obj);
            if (job->objects)
                job->objects[at] = obj;
        }
    }
    free(dirs);
    return NULL;
}

int rt_render_certify(rt_render *r, unsigned char *map, int *objects)
{
    cert_job job;
    pthread_t ids[256];
    pthread_attr_t attr;
    int threads, started = 0, i;
    job.r = r;
    job.map = map;
    job.objects = objects;
    rt_render_shape(r, &job.y0, &job.y1, &job.width, &job.spp, &threads);
    job.next = job.y0;
    if (threads > 256)
        threads = 256;
    if (pthread_mutex_init(&job.lock, NULL) != 0)
        return -1;
    pthread_attr_init(&attr);
    pthread_attr_setstacksize(&attr, (size_t)16 << 20);
    for (i = 0; i < threads; ++i)
        if (pthread_create(&ids[started], &attr, cert_worker, &job) == 0)
            ++started;
    pthread_attr_destroy(&attr);
    for (i = 0; i < started; ++i)
        pthread_join(ids[i], NULL);
    pthread_mutex_destroy(&job.lock);
    return started > 0 && job.next >= job.y1 ? 0 : -1;
}
