/* Optics and shading: reflection, refraction (Snell), exact Fresnel, Beer-Lambert absorption, shadow rays
 * that pass through glass attenuated by its transparency and absorption, and the Whitted recursion.
 *
 * Light model (deliberately the classic one, documented in docs/tracer.md):
 *   colour = (1 - transparency) * [ambient * base + sum over lights of T_shadow * light *
 *                                   (diffuse * base * max(0, n.l) + specular * max(0, n.h)^shininess)]
 *          + (reflectivity + transparency * F) * reflected + transparency * (1 - F) * refracted
 * with F the Fresnel reflectance (1 under total internal reflection), base the material colour or checker.
 * Everything a ray sees while inside a transparent solid is attenuated by exp(-absorption * distance).
 */
#include "tracer_internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define RT_MIN_WEIGHT 1e-3 /* secondary rays contributing less than this to the pixel are not cast */
#define RT_MAX_SHADOW_CROSSINGS 32

static void normalize3(double v[3])
{
    double l = sqrt(rt_dot(v, v));
    if (l > 0.0) {
        v[0] /= l;
        v[1] /= l;
        v[2] /= l;
    }
}

void rt_reflect(const double d[3], const double n[3], double r[3])
{
    double u[3], k;
    int a;
    memcpy(u, d, sizeof u);
    normalize3(u);
    k = 2.0 * rt_dot(u, n);
    for (a = 0; a < 3; ++a)
        r[a] = u[a] - k * n[a];
    normalize3(r);
}

int rt_refract(const double d[3], const double n[3], double eta, double t[3])
{
    double u[3], ci, k;
    int a;
    memcpy(u, d, sizeof u);
    normalize3(u);
    ci = -rt_dot(u, n);
    k = 1.0 - eta * eta * (1.0 - ci * ci);
    if (k < 0.0)
        return 0;
    for (a = 0; a < 3; ++a)
        t[a] = eta * u[a] + (eta * ci - sqrt(k)) * n[a];
    normalize3(t);
    return 1;
}

double rt_fresnel(double ci, double eta)
{
    double st2, ct, rs, rp;
    if (ci < 0.0)
        ci = -ci;
    if (ci > 1.0)
        ci = 1.0;
    st2 = eta * eta * (1.0 - ci * ci);
    if (st2 >= 1.0)
        return 1.0;
    ct = sqrt(1.0 - st2);
    rs = (eta * ci - ct) / (eta * ci + ct);
    rp = (ci - eta * ct) / (ci + eta * ct);
    return 0.5 * (rs * rs + rp * rp);
}

void rt_spawn_origin(const rt_hit *h, const double d[3], double origin[3])
{
    double side = rt_dot(d, h->n) >= 0.0 ? h->err : -h->err;
    int a;
    for (a = 0; a < 3; ++a)
        origin[a] = h->p[a] + side * h->n[a];
}

/* ------------------------------------------------------------------ shading */

typedef struct rt_media {
    int n;
    int mat[RT_MAX_MEDIA];
} rt_media;

typedef struct rt_tracer {
    const rt_scene *s;
    int max_depth;
    double *stats;
} rt_tracer;

/* x^e for the Phong highlight, x in (0, 1]: a whole exponent up to 1024 (the usual shininess) by repeated
 * squaring, a few multiplications instead of a call to pow; any other by pow. */
static double highlight_power(double x, double e)
{
    if (e >= 0.0 && e <= 1024.0 && e == (double)(int)e) {
        double r = 1.0;
        int k = (int)e;
        for (; k > 0; k >>= 1, x *= x)
            if (k & 1)
                r *= x;
        return r;
    }
    return pow(x, e);
}

static double media_ior(const rt_scene *s, const rt_media *m)
{
    return m->n > 0 ? s->materials[m->mat[m->n - 1]].ior : 1.0;
}

static void media_remove(rt_media *m, int mat)
{
    int i;
    for (i = m->n - 1; i >= 0; --i)
        if (m->mat[i] == mat) {
            memmove(m->mat + i, m->mat + i + 1, (size_t)(m->n - 1 - i) * sizeof(int));
            m->n--;
            return;
        }
}

/* The colour of the surface at h before lighting; back: the ray sees the side the normal points away from. */
static void base_colour(const rt_material *m, const rt_hit *h, int back, double c[3])
{
    if (back && m->two_sided != 0.0) {
        memcpy(c, m->inside, 3 * sizeof(double));
    } else if (m->checker_scale > 0.0) {
        /* A 3-D checker in object space, evaluated a little below the surface (a fraction of a cell) so a
         * surface lying exactly on a cell boundary, like the plane y = 0, does not speckle. The cell index
         * floor(q) of each axis is an integer; the colour is color where their sum is even. Below 2^53 the
         * parity of an integer-valued double is that of its conversion; at and above, every double is even. A
         * cell index that is not finite (q overflowed) gives color2. */
        int a, odd = 0;
        for (a = 0; a < 3; ++a) {
            double q = (h->po[a] - 1e-3 * m->checker_scale * h->no[a]) / m->checker_scale, k = fabs(floor(q));
            if (!(k <= DBL_MAX)) {
                odd = 1;
                break;
            }
            if (k < 0x1p53)
                odd ^= (int)((long long)k & 1);
        }
        memcpy(c, odd ? m->color2 : m->color, 3 * sizeof(double));
    } else {
        memcpy(c, m->color, 3 * sizeof(double));
    }
}

/* Fraction of a light's colour that reaches p through the scene (0 behind an opaque object). Transparent
 * objects let transparency through at each entry and absorb inside; refraction does not bend shadow rays. */
static void shadow_transmittance(const rt_tracer *tr, const rt_hit *from, const double light[3], double T[3])
{
    const rt_scene *s = tr->s;
    double q[3], dd[3];
    rt_hit h;
    rt_pending ph;
    int i, a, skip = rt_spawn_skip(s, from);
    T[0] = T[1] = T[2] = 1.0;
    for (a = 0; a < 3; ++a)
        dd[a] = light[a] - from->p[a];
    rt_spawn_origin(from, dd, q);
    for (i = 0; i < RT_MAX_SHADOW_CROSSINGS; ++i) {
        const rt_material *m;
        for (a = 0; a < 3; ++a)
            dd[a] = light[a] - q[a];
        if (tr->stats)
            tr->stats[RT_RAYS_SHADOW] += 1.0;
        RT_TRACE_KIND(s, RT_RAYS_SHADOW);
        /* any opaque hit before the light is full shadow, whether or not it is the closest */
        if (!rt_scene_closest(s, q, dd, 0.0, 1.0, RT_ANY_OPAQUE, skip, &ph))
            return;
        m = &s->materials[s->nodes[ph.leaf].material];
        if (m->transparency <= 0.0) {
            T[0] = T[1] = T[2] = 0.0;
            return;
        }
        rt_finish_hit(s, &ph, q, dd, &h, NULL);
        if (h.entering) {
            for (a = 0; a < 3; ++a)
                T[a] *= m->transparency;
        } else {
            double len = h.t * sqrt(rt_dot(dd, dd));
            for (a = 0; a < 3; ++a)
                T[a] *= exp(-m->absorption[a] * len);
        }
        if (T[0] + T[1] + T[2] < 1e-4) {
            T[0] = T[1] = T[2] = 0.0;
            return;
        }
        rt_spawn_origin(&h, dd, q);
        skip = rt_spawn_skip(s, &h);
    }
}

/* One hit as the shading steps of trace see it. */
typedef struct rt_surface {
    rt_hit h;
    /* h.err is worked out (rt_hit_error) only before a ray leaves h: a surface lit by no light and neither
     * reflecting nor refracting never needs it */
    rt_hit_lazy lazy;
    const rt_material *m;
    double u[3];  /* the unit ray direction */
    double nf[3]; /* the unit normal turned to face the ray */
    double dl;    /* |d|: world length per unit of t (absorb needs the length travelled) */
    int back;     /* the ray sees the side the normal points away from */
} rt_surface;

static void trace(const rt_tracer *tr, const double o[3], const double d[3], int skip, int depth, const rt_media *media,
                  double weight, double rgb[3]);

/* The ray's unit direction, which side of the surface it sees, and the normal turned towards it. */
static inline void face_the_ray(rt_surface *sf, const double d[3])
{
    int a;
    sf->dl = sqrt(rt_dot(d, d));
    for (a = 0; a < 3; ++a)
        sf->u[a] = d[a] / sf->dl;
    sf->back = !(rt_dot(sf->h.n, sf->u) < 0.0);
    if (!sf->back)
        memcpy(sf->nf, sf->h.n, sizeof sf->nf);
    else
        for (a = 0; a < 3; ++a)
            sf->nf[a] = -sf->h.n[a];
}

/* The Phong highlight's weight for a light in the unit direction L / ll. */
static inline double specular_term(const rt_surface *sf, const double L[3], double ll)
{
    double hv[3], ndh;
    int a;
    for (a = 0; a < 3; ++a)
        hv[a] = L[a] / ll - sf->u[a];
    normalize3(hv);
    ndh = rt_dot(sf->nf, hv);
    return ndh > 0.0 ? sf->m->specular * highlight_power(ndh, sf->m->shininess) : 0.0;
}

/* Adds one light's diffuse and specular light at the hit to local, times what of it the scene lets through. */
static inline void add_light(const rt_tracer *tr, rt_surface *sf, const double *lp, const double base[3],
                             double local[3])
{
    const rt_material *m = sf->m;
    const double *lc = lp + 3;
    double L[3], ll, ndl, T[3], spec = 0.0;
    int a;
    for (a = 0; a < 3; ++a)
        L[a] = lp[a] - sf->h.p[a];
    ll = sqrt(rt_dot(L, L));
    if (!(ll > 0.0))
        return;
    ndl = rt_dot(sf->nf, L) / ll;
    if (ndl <= 0.0)
        return; /* the light is behind the surface as seen from the ray */
    rt_hit_error(tr->s, &sf->h, &sf->lazy);
    shadow_transmittance(tr, &sf->h, lp, T);
    if (T[0] + T[1] + T[2] <= 0.0)
        return;
    if (m->specular > 0.0)
        spec = specular_term(sf, L, ll);
    for (a = 0; a < 3; ++a)
        local[a] += T[a] * lc[a] * (m->diffuse * base[a] * ndl + spec);
}

/* The opaque part of the colour: (1 - transparency) x (ambient + the lights that reach the hit). */
static inline void local_colour(const rt_tracer *tr, rt_surface *sf, double col[3])
{
    const rt_scene *s = tr->s;
    const rt_material *m = sf->m;
    double base[3], local[3];
    int a, l;
    base_colour(m, &sf->h, sf->back, base);
    for (a = 0; a < 3; ++a)
        local[a] = m->ambient * base[a];
    if (m->transparency < 1.0)
        for (l = 0; l < s->nlights; ++l)
            add_light(tr, sf, s->lights + 6 * l, base, local);
    for (a = 0; a < 3; ++a)
        col[a] = (1.0 - m->transparency) * local[a];
}

/* Where a transparent surface sends the refracted ray: the media stack behind the surface (next), the
 * direction tdir and the Fresnel reflectance *F (1 under total internal reflection). Returns 0 under total
 * internal reflection, else 1. */
static inline int refraction(const rt_scene *s, const rt_surface *sf, const rt_media *media, rt_media *next,
                             double tdir[3], double *F)
{
    double ci = -rt_dot(sf->u, sf->nf), n1, n2;
    int can_refract;
    if (sf->h.entering) {
        n1 = media_ior(s, media);
        n2 = sf->m->ior;
        if (next->n < RT_MAX_MEDIA)
            next->mat[next->n++] = sf->h.material;
    } else {
        n1 = sf->m->ior;
        media_remove(next, sf->h.material);
        n2 = media_ior(s, next);
    }
    can_refract = rt_refract(sf->u, sf->nf, n1 / n2, tdir);
    *F = can_refract ? rt_fresnel(ci, n1 / n2) : 1.0;
    return can_refract;
}

/* Traces the secondary ray leaving the hit along dir (inside media) and adds k times its colour to col. */
static inline void add_secondary(const rt_tracer *tr, rt_surface *sf, const double dir[3], int depth,
                                 const rt_media *media, double weight, double k, double col[3])
{
    double q[3], c[3];
    int a;
    rt_hit_error(tr->s, &sf->h, &sf->lazy);
    rt_spawn_origin(&sf->h, dir, q);
    if (tr->stats)
        tr->stats[RT_RAYS_SECONDARY] += 1.0;
    trace(tr, q, dir, rt_spawn_skip(tr->s, &sf->h), depth + 1, media, weight * k, c);
    for (a = 0; a < 3; ++a)
        col[a] += k * c[a];
}

/* Adds the mirror and glass part of the colour: the reflected and the refracted ray, each cast only when its
 * share of the pixel (weight) is above RT_MIN_WEIGHT. */
static inline void add_reflection_refraction(const rt_tracer *tr, rt_surface *sf, int depth, const rt_media *media,
                                             double weight, double col[3])
{
    const rt_material *m = sf->m;
    double F = 0.0, kr, kt, tdir[3] = {0.0, 0.0, 0.0};
    rt_media next = *media;
    int can_refract = 0;
    if (m->transparency > 0.0)
        can_refract = refraction(tr->s, sf, media, &next, tdir, &F);
    kr = m->reflectivity + m->transparency * F;
    if (kr > 1.0)
        kr = 1.0;
    kt = can_refract ? m->transparency * (1.0 - F) : 0.0;
    if (kr * weight > RT_MIN_WEIGHT) {
        double r[3];
        rt_reflect(sf->u, sf->nf, r);
        add_secondary(tr, sf, r, depth, media, weight, kr, col);
    }
    if (kt * weight > RT_MIN_WEIGHT)
        add_secondary(tr, sf, tdir, depth, &next, weight, kt, col);
}

/* Beer-Lambert over the segment just travelled (len world units), if it ran inside an absorbing medium. */
static inline void absorb(const rt_scene *s, const rt_media *media, double len, double col[3])
{
    const rt_material *mm;
    int a;
    if (media->n == 0)
        return;
    mm = &s->materials[media->mat[media->n - 1]];
    for (a = 0; a < 3; ++a)
        col[a] *= exp(-mm->absorption[a] * len);
}

/* The colour seen along o + t d; skip: an object the ray need not test (rt_spawn_skip), or -1. */
static void trace(const rt_tracer *tr, const double o[3], const double d[3], int skip, int depth, const rt_media *media,
                  double weight, double rgb[3])
{
    const rt_scene *s = tr->s;
    rt_surface sf;
    rt_pending ph;
    double col[3];

    RT_TRACE_KIND(s, depth == 0 ? RT_RAYS_PRIMARY : RT_RAYS_SECONDARY);
    if (!rt_scene_closest(s, o, d, 0.0, INFINITY, RT_CLOSEST, skip, &ph)) {
        memcpy(rgb, s->background, 3 * sizeof(double));
        return;
    }
    rt_finish_hit(s, &ph, o, d, &sf.h, &sf.lazy);
    sf.m = &s->materials[sf.h.material];
    face_the_ray(&sf, d);
    local_colour(tr, &sf, col);
    if (depth < tr->max_depth)
        add_reflection_refraction(tr, &sf, depth, media, weight, col);
    absorb(s, media, sf.h.t * sf.dl, col);
    memcpy(rgb, col, 3 * sizeof(double));
}

void rt_trace_ray(const rt_scene *s, const double o[3], const double d[3], int max_depth, double rgb[3],
                  double stats[RT_NSTATS])
{
    rt_tracer tr;
    rt_media media;
    tr.s = s;
    tr.max_depth = max_depth < 0 ? 0 : (max_depth > RT_MAX_DEPTH ? RT_MAX_DEPTH : max_depth);
    tr.stats = stats;
    media.n = 0;
    if (stats)
        stats[RT_RAYS_PRIMARY] += 1.0;
    if (!s->committed) {
        rgb[0] = rgb[1] = rgb[2] = 0.0;
        return;
    }
    trace(&tr, o, d, -1, 0, &media, 1.0, rgb);
}
