/* Rays against a committed scene: the closest-hit query (unbounded objects, then the BVH), and finishing a hit
 * (normal, orientation, the error bound of the hit point). The ray's set-up and its slab clip are
 * tracer_internal.h's (rt_ray_init, rt_clip_box), shared with the CSG's spans.
 */
#include "tracer_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ rays and boxes */

/* The BVH's box test: rt_clip_box with the ray's precomputed inverse direction and no face codes. */
static int ray_box(const double box[6], const rt_ray *r, double *t0, double *t1)
{
    return rt_clip_slabs(box, r->o, r->d, r->inv, t0, t1, NULL, NULL);
}

/* ------------------------------------------------------------------ hits */

/* Safety factors of the hit-point error bound (see rt_finish_hit); chosen by the measurement in
 * tests/c/tracer_offsets.c, which reports how many self-hits each choice leaves. */
#ifndef RT_ERR_OBJECT
#define RT_ERR_OBJECT 32.0 /* x eps x (degree + 1) x magnitude of the object-space computation */
#endif
#ifndef RT_ERR_WORLD
#define RT_ERR_WORLD 32.0 /* x eps x magnitude of the world-space computation */
#endif

/* Rounding noise of f near the hit as the root solver sees it. The solver expands f(o + t d) around a point
 * of the ray next to the object (shape.c's shift point: nearest the centre of the box's finite axes, else the
 * coordinate origin). Two estimates, the larger wins: Horner's running error bound eps * sum |c_k| |tau|^k
 * at the root's offset tau from that point, and the disagreement between that expansion and the generated
 * value(p) -- two roundings of the same number, which catches cancellation inside the coefficients (a
 * cubed factor expanded into monomials) that the first estimate cannot see. Measured by
 * tests/c/tracer_offsets.c. */
static double solver_noise(const rt_node *n, const rt_hit_lazy *lz, const double po[3], double fp, double t)
{
    double sum = 0.0, horner;
    int a, k, deg = n->shape->degree;
    if (lz->noise_known) { /* the solve that found the hit handed its expansion over (rt_object_hit) */
        sum = lz->noise_sum;
        horner = lz->noise_val;
    } else { /* a CSG leaf's root: an expansion by shape.c's rule (without its clamp to the clipped range) */
        ig_shape_expansion ex;
        double os[3];
        ex.ts = ig_shape_shift_point(&n->prep, lz->oo, lz->od, -INFINITY, INFINITY);
        for (a = 0; a < 3; ++a)
            os[a] = lz->oo[a] + ex.ts * lz->od[a];
        n->shape->coeffs(os, lz->od, n->params, ex.c);
        rt_expansion_noise(&ex, deg, t, &sum, &horner);
    }
    /* The secondary ray will be solved from its own shift point, not this one; when this ray's shift point
     * happens to sit at the hit, the sum above sees only |f(po)| ~ 0. So also expand along the segment from
     * the box centre (the coordinate origin on open axes) to po: the noise any ray solved inside the box
     * meets near po. */
    {
        double seg[3], c2[IG_MAX_DEGREE + 1], sum2 = 0.0;
        for (a = 0; a < 3; ++a)
            seg[a] = po[a] - n->prep.centre[a];
        n->shape->coeffs(n->prep.centre, seg, n->params, c2);
        for (k = 0; k <= deg; ++k)
            sum2 += fabs(c2[k]);
        if (sum2 > sum)
            sum = sum2;
    }
    sum = RT_ERR_OBJECT * DBL_EPSILON * (double)(deg + 1) * sum;
    horner = RT_ERR_OBJECT * fabs(horner - fp);
    if (!isfinite(sum) || !isfinite(horner))
        return 0.0;
    return sum > horner ? sum : horner;
}

/* How far from po the surface can be, given |f(po)| plus its noise: along the direction u (the normal, or
 * the ray at a singular point) f(po + s u) = c_0 + c_1 s + c_2 s^2 + ...; the smallest s at which one term
 * c_k s^k reaches |c_0| + noise. With k = 1 this is the familiar (|f| + noise) / |grad f|; the higher terms
 * keep the estimate finite where grad f vanishes (a cusp, or the heart's singular equator). They can only
 * lower it, so where the first-order distance is already below RT_DIST_FIRST_ORDER of the object's size it
 * stands on its own (an error bound that much larger than needed moves no secondary ray visibly), and the
 * expansion -- a full set of coefficients, the costliest part of a hit's error -- is skipped. gl is |grad f|
 * when u is the normal, else 0. */
#ifndef RT_DIST_FIRST_ORDER
#define RT_DIST_FIRST_ORDER 1e-6
#endif
static double distance_bound(const rt_node *n, const double po[3], const double u[3], double gl, double level)
{
    double c[IG_MAX_DEGREE + 1], best = INFINITY, best_pow = INFINITY;
    int k, deg = n->shape->degree;
    if (gl > 0.0) {
        double first = level / gl, size = ig_max(rt_maxabs3(po), n->half);
        if (deg == 1 || first <= RT_DIST_FIRST_ORDER * size)
            return isfinite(first) ? first : 0.0;
    }
    n->shape->coeffs(po, u, n->params, c);
    for (k = 1; k <= deg; ++k) {
        double q;
        if (k > 1 && isfinite(best))
            best_pow *= best; /* best^k */
        if (!(c[k] != 0.0) || !isfinite(c[k]))
            continue;
        q = level / fabs(c[k]);
        if (k == 1) {
            best = q;
            best_pow = q;
        } else if (q < best_pow) { /* only then is q^(1/k) below the best so far */
            best = pow(q, 1.0 / k);
            best_pow = q;
        }
    }
    return isfinite(best) ? best : 0.0;
}

/* The hit point in world and object space, and the rays and solver noise rt_hit_error will need kept in lz. */
static inline void hit_points(const rt_node *n, const rt_pending *pd, const double o[3], const double d[3], rt_hit *hit,
                              rt_hit_lazy *lz)
{
    double t = pd->t;
    int a;
    rt_to_object(n, o, d, lz->oo, lz->od);
    memcpy(lz->o, o, sizeof lz->o);
    memcpy(lz->d, d, sizeof lz->d);
    for (a = 0; a < 3; ++a) {
        hit->p[a] = o[a] + t * d[a];
        hit->po[a] = lz->oo[a] + t * lz->od[a];
        lz->u[a] = 0.0;
    }
    lz->f = 0.0;
    lz->gl = 0.0;
    lz->noise_known = pd->noise_known;
    lz->noise_sum = pd->noise_sum;
    lz->noise_val = pd->noise_val;
}

/* The object-space normal g, not unit: grad f on the surface, the outward axis on a face of the bounds box.
 * On the surface also f at po and the direction rt_hit_error measures the distance to f = 0 along (into lz).
 * Returns 1 at a singular point: grad f zero or not finite, or f not finite. */
static inline int object_normal(const rt_node *n, int face, const double po[3], rt_hit_lazy *lz, double g[3])
{
    double f, gl;
    int a;
    if (face != 0) {
        g[0] = g[1] = g[2] = 0.0;
        g[abs(face) - 1] = face > 0 ? 1.0 : -1.0;
        return 0;
    }
    f = n->shape->value(po, n->params);
    n->shape->gradient(po, n->params, g);
    gl = sqrt(rt_dot(g, g));
    lz->f = f;
    if (!(gl > 0.0) || !isfinite(gl) || !isfinite(f)) {
        double l = sqrt(rt_dot(lz->od, lz->od));
        for (a = 0; a < 3; ++a)
            lz->u[a] = lz->od[a] / l;
        return 1;
    }
    for (a = 0; a < 3; ++a)
        lz->u[a] = g[a] / gl;
    lz->gl = gl;
    return 0;
}

/* Turns the normals nw and g to their side and returns whether the ray enters the solid at the hit; *flipped: 1 when
 * they were turned around. */
static inline int orient_normals(const rt_pending *pd, int singular, const double d[3], double nw[3], double g[3],
                                 int *flipped)
{
    int a, entering = pd->entering;
    *flipped = 0;
    if (singular) {
        /* grad f = 0 (a cusp, an apex): no normal exists; face the ray so shading stays finite. */
        double len = sqrt(rt_dot(d, d));
        for (a = 0; a < 3; ++a)
            nw[a] = -d[a] / len;
        g[0] = g[1] = g[2] = 0.0;
        if (!pd->entering_known)
            entering = 1;
    } else if (!pd->entering_known) {
        entering = rt_dot(nw, d) < 0.0;
    } else if ((rt_dot(nw, d) < 0.0) != (entering != 0)) {
        /* CSG: orient by the interval end (this also flips a subtracted part's normal). */
        for (a = 0; a < 3; ++a) {
            nw[a] = -nw[a];
            g[a] = -g[a];
        }
        *flipped = 1;
    }
    return entering;
}

void rt_finish_hit(const rt_scene *s, const rt_pending *pd, const double o[3], const double d[3], rt_hit *hit,
                   rt_hit_lazy *lazy)
{
    const rt_node *n = &s->nodes[pd->leaf];
    rt_hit_lazy own, *lz = lazy ? lazy : &own;
    double g[3], nw[3], len;
    int a, singular, entering, flipped;

    hit_points(n, pd, o, d, hit, lz);
    singular = object_normal(n, pd->face, hit->po, lz, g);
    if (!singular && !ig_affine_normal(n->minv, g, nw)) /* normals map by the inverse transpose */
        singular = 1;
    entering = orient_normals(pd, singular, d, nw, g, &flipped);
    memcpy(hit->n, nw, sizeof nw);
    if (pd->face == 0 && !singular) {
        /* g / |g| is object_normal's lz->u, turned like g (-a / b == -(a / b)): no second square root */
        for (a = 0; a < 3; ++a)
            hit->no[a] = flipped ? -lz->u[a] : lz->u[a];
    } else {
        len = sqrt(rt_dot(g, g));
        for (a = 0; a < 3; ++a)
            hit->no[a] = len > 0.0 ? g[a] / len : nw[a];
    }
    hit->err = 0.0;
    hit->t = pd->t;
    hit->object = pd->object;
    hit->leaf = pd->leaf;
    hit->face = pd->face;
    hit->material = n->material;
    hit->entering = entering != 0;
    hit->singular = singular;
    lz->pending = 1;
    if (!lazy)
        rt_hit_error(s, hit, lz);
}

void rt_hit_error(const rt_scene *s, rt_hit *hit, rt_hit_lazy *lz)
{
    const rt_node *n = &s->nodes[hit->leaf];
    double dist = 0.0, mag_o, mag_w, td[3], tod[3], tr[3], t = hit->t;
    int a;
    if (!lz->pending)
        return;
    lz->pending = 0;
    if (hit->face == 0) {
        double f = lz->f, level;
        level = isfinite(f) ? fabs(f) + solver_noise(n, lz, hit->po, f, t) : 0.0;
        /* distance of the computed point from f = 0, including how far the solver's noise can move a root */
        dist = level > 0.0 ? distance_bound(n, hit->po, lz->u, lz->gl, level) : 0.0;
    }
    /* Error bound of the hit point, in world units. The object-space part: the measured distance |f|/|grad f|
     * of the computed point, plus the rounding noise of evaluating f and of forming o' + t d' (relative to
     * the magnitudes involved); M stretches it by at most its norm. The world part: rounding of o + t d and
     * of the transforms. */
    for (a = 0; a < 3; ++a) {
        td[a] = t * lz->d[a];
        tod[a] = t * lz->od[a];
    }
    mag_o = rt_maxabs3(lz->oo) + rt_maxabs3(tod) + rt_maxabs3(hit->po);
    tr[0] = n->m[3];
    tr[1] = n->m[7];
    tr[2] = n->m[11];
    mag_w = rt_maxabs3(lz->o) + rt_maxabs3(td) + rt_maxabs3(hit->p) + rt_maxabs3(tr);
    hit->err = n->mnorm * (dist + RT_ERR_OBJECT * DBL_EPSILON * (double)(n->shape->degree + 1) * mag_o) +
               RT_ERR_WORLD * DBL_EPSILON * mag_w;
}

int rt_spawn_skip(const rt_scene *s, const rt_hit *h) { return s->flat[h->object] ? h->object : -1; }

/* One closest-hit (or any-opaque-hit) search along a ray: what rt_scene_closest's steps share. */
typedef struct {
    const rt_scene *s;
    rt_ray ray;
    double tmin, best; /* hits are looked for in [tmin, best); best shrinks as they are found */
    int mode, skip, found;
    rt_pending *out;
} rt_search;

/* Object obj's hit, kept when it is closer than the best so far (rt_object_hit only reports t < best). Returns
 * 1 when the search is over: in RT_ANY_OPAQUE mode, a hit on an opaque material. */
static inline int search_take(rt_search *q, int obj)
{
    rt_pending h;
    if (obj == q->skip || !rt_object_hit(q->s, obj, &q->ray, q->tmin, q->best, q->mode == RT_ANY_OPAQUE, &h))
        return 0;
    *q->out = h;
    q->best = h.t;
    q->found = 1;
    return q->mode == RT_ANY_OPAQUE && rt_leaf_opaque(q->s, &q->s->nodes[h.leaf]);
}

/* The objects of BVH leaf b. A leaf's box holds its objects' boxes, which may be far apart (a scene's objects to
 * the left and right of the one in the middle): each object's own box first, before its solve sets up. */
static inline int search_leaf(rt_search *q, const rt_bvh_node *b)
{
    const rt_scene *s = q->s;
    int i;
    for (i = b->first; i < b->first + b->count; ++i) {
        double o0 = q->tmin, o1 = q->best;
        if (b->count > 1 && !ray_box(s->nodes[s->objects[s->order[i]]].wbox, &q->ray, &o0, &o1))
            continue;
        if (search_take(q, s->order[i]))
            return 1;
    }
    return 0;
}

/* The children of inner node b that the ray enters before the best hit, pushed with their entry t, the nearer
 * child last so that it is visited first. */
static inline int search_push(const rt_search *q, const rt_bvh_node *b, int *stack, double *entry, int sp)
{
    const rt_bvh_node *l = &q->s->bvh[b->left], *r = &q->s->bvh[b->right];
    double la = q->tmin, lb = q->best, ra = q->tmin, rb = q->best;
    int lhit = ray_box(l->box, &q->ray, &la, &lb);
    int rhit = ray_box(r->box, &q->ray, &ra, &rb);
    if (lhit && rhit && la > ra) {
        stack[sp] = b->left;
        entry[sp++] = la;
        stack[sp] = b->right;
        entry[sp++] = ra;
        return sp;
    }
    if (rhit) {
        stack[sp] = b->right;
        entry[sp++] = ra;
    }
    if (lhit) {
        stack[sp] = b->left;
        entry[sp++] = la;
    }
    return sp;
}

int rt_scene_closest(const rt_scene *s, const double o[3], const double d[3], double tmin, double tmax, int mode,
                     int skip, rt_pending *out)
{
    int i, sp = 0, stack[128];
    double entry[128];
    rt_search q;
    if (!s->committed)
        return 0;
    if (!isfinite(d[0]) || !isfinite(d[1]) || !isfinite(d[2]) || !isfinite(o[0]) || !isfinite(o[1]) || !isfinite(o[2]))
        return 0;
    RT_TRACE_QUERY(s, o, d, tmin, tmax, mode, skip);
    q.s = s;
    rt_ray_init(&q.ray, o, d, s->far, s->unit_rays);
    q.tmin = tmin;
    q.best = tmax;
    q.mode = mode;
    q.skip = skip;
    q.found = 0;
    q.out = out;
    for (i = 0; i < s->nunbounded; ++i)
        if (search_take(&q, s->unbounded[i]))
            return 1;
    /* Each stack entry carries the t where the ray enters its box, so a node is clipped once and skipped
     * when a closer hit has been found since it was pushed. */
    if (s->nbvh > 0) {
        double t0 = tmin, t1 = q.best;
        if (ray_box(s->bvh[0].box, &q.ray, &t0, &t1)) {
            stack[sp] = 0;
            entry[sp++] = t0;
        }
    }
    while (sp > 0) {
        const rt_bvh_node *b;
        --sp;
        if (entry[sp] > q.best)
            continue;
        b = &s->bvh[stack[sp]];
        if (b->left < 0) {
            if (search_leaf(&q, b))
                return 1;
        } else if (sp + 2 <= (int)(sizeof stack / sizeof stack[0])) {
            sp = search_push(&q, b, stack, entry, sp);
        }
    }
    return q.found;
}

int rt_scene_intersect(const rt_scene *s, const double o[3], const double d[3], double tmin, double tmax, rt_hit *hit)
{
    rt_pending h;
    if (!rt_scene_closest(s, o, d, tmin, tmax, RT_CLOSEST, -1, &h))
        return 0;
    rt_finish_hit(s, &h, o, d, hit, NULL);
    return 1;
}
