/* Data structures shared by the tracer_*.c files; not part of the public interface (see tracer.h). */
#ifndef IMPLGEN_TRACER_INTERNAL_H
#define IMPLGEN_TRACER_INTERNAL_H

#include "numerics.h"
#include "tracer.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

typedef struct rt_node {
    int kind;        /* RT_LEAF, RT_UNION, RT_INTERSECTION, RT_DIFFERENCE */
    int left, right; /* children (CSG) */
    int material;    /* -1: none given (the Python side resolves inheritance before it gets here) */
    int depth;       /* CSG nesting depth below this node */
    /* leaf */
    const ig_shape *shape;
    double *params;     /* owned copy, shape->nparams entries */
    double m[12];       /* object -> world */
    double minv[12];    /* world -> object */
    double mnorm;       /* Frobenius norm of M's linear part: bounds how much M stretches a distance */
    int identity;       /* M is exactly the identity: rays need no transforming */
    double obox[6];     /* object-space bounds box, as the spec gives it (a clip does not change it) */
    int obounded;       /* the spec gives bounds (some sides may still be infinite) */
    ig_shape_prep prep; /* shape.c's per-shape clip and shift data, worked out once (ig_shape_solve) */
    double half;        /* the largest half-extent of prep's finite box axes, 0 without one (rt_hit_error) */
    int clip;           /* RT_CLIP_*: a top-level leaf's surface is shown only inside the clip region */
    double clip_c[3];   /* the clip's centre (object space) */
    double clip_r;      /* its radius, or its half-edge */
    /* any node (after commit) */
    double wbox[6]; /* world-space box, slightly padded; a side is infinite where the node is open that way */
    int wbounded;   /* every side of wbox is finite: the object goes into the BVH */
} rt_node;

typedef struct rt_bvh_node {
    double box[6];
    int left, right;  /* children; -1 for a leaf */
    int first, count; /* leaf: bounded objects order[first .. first + count) */
} rt_bvh_node;

struct rt_scene {
    rt_node *nodes;
    int nnodes, cap_nodes;
    int *objects; /* node index of each top-level object */
    int nobjects, cap_objects;
    rt_material *materials;
    int nmaterials, cap_materials;
    double *lights; /* 6 per light: position, colour x intensity */
    int nlights, cap_lights;
    double eye[3], look_at[3], up[3], vfov;
    double background[3];
    /* after commit */
    int committed;
    double far;     /* stands in for t = infinity on unbounded shapes: 1e5 x the scene's size */
    int *unbounded; /* objects outside the BVH */
    int nunbounded;
    unsigned char *flat; /* per object: a top-level leaf of degree 1 (part of a plane), which no ray leaving
                            it can meet again: rays spawned from it need not test it (rt_scene_closest) */
    int unit_rays;       /* some leaf solves along the world ray's unit direction (an identity leaf in a CSG tree,
                            or an identity top-level leaf that the plane path does not take): every ray works it
                            out at once (rt_ray_init); otherwise only a plane path's rare fallback needs it */
    int *order;          /* bounded objects in BVH leaf order */
    rt_bvh_node *bvh;
    int nbvh;
    char error[256];
#ifdef RT_TRACE
    struct rt_trace_log *trace; /* the instrumented build's record of a render's rays (tracer_floor.c), or NULL */
#endif
};

/* One end of an inside-interval: where it is and which surface makes it. */
typedef struct rt_end {
    double t;
    int leaf; /* node index of the leaf, -1: open (the ray's range starts/ends inside) */
    int face; /* 0: the surface f = 0; +-(axis + 1): outward face of the leaf's bounds box */
} rt_end;

typedef struct rt_span {
    rt_end in, out;
} rt_span;

/* The closest hit before its normal and error bound are worked out (rt_finish_hit), so a shadow ray that
 * meets an opaque object can stop without that cost. */
typedef struct rt_pending {
    double t;
    int object, leaf, face, entering, entering_known;
    /* noise_known: the solve that found t handed over its expansion's view of f there (see solver_noise):
     * noise_sum = sum |c_k| |tau|^k and noise_val = the expansion's value at the root's offset tau */
    int noise_known;
    double noise_sum, noise_val;
} rt_pending;

/* A world ray with what every object test along it would otherwise work out again. */
typedef struct rt_ray {
    double o[3], d[3];
    double inv[3]; /* 1 / d[a]; not used where d[a] == 0 */
    double len;    /* |d| */
    double u[3];   /* d / |d|: the unit direction an identity leaf solves along (when unit; see rt_ray_unit) */
    int unit;      /* u is worked out */
    double far_t;  /* far / |d|: where an unbounded object's solve stops (INFINITY when d = 0) */
} rt_ray;

/* What rt_hit_error needs to work out hit->err after rt_finish_hit, kept so that a hit that spawns no ray
 * never pays for it. */
typedef struct rt_hit_lazy {
    int pending;         /* 1: hit->err is not computed yet */
    double o[3], d[3];   /* the world ray */
    double oo[3], od[3]; /* the ray in the leaf's object space */
    double u[3];         /* the unit direction distance_bound expands along (normal, or ray at a singular point) */
    double f;            /* f at the object-space hit point */
    double gl;           /* |grad f| there when u is the normal, else 0 */
    int noise_known;     /* the pending hit's noise_known, noise_sum and noise_val */
    double noise_sum, noise_val;
} rt_hit_lazy;

/* A leaf whose material stops light: a shadow ray that meets it is in full shadow (RT_ANY_OPAQUE). */
static inline int rt_leaf_opaque(const rt_scene *s, const rt_node *n)
{
    return n->material >= 0 && s->materials[n->material].transparency <= 0.0;
}

/* Closest-hit query modes. RT_ANY_OPAQUE: the same, except that the search stops at the first hit on an
 * opaque material it meets (a shadow ray: any opaque hit in range is full shadow), which may not be the
 * closest one, and whose t may be unrefined (rt_object_hit's `any`); a hit on a transparent material is
 * still the closest hit, refined. */
enum { RT_CLOSEST = 0, RT_ANY_OPAQUE = 1 };
/* The object a ray spawned at hit h need not test (rt_scene_closest's `skip`): h's object when it is flat
 * (a plane meets a line once, and that is h itself), else -1. */
int rt_spawn_skip(const rt_scene *s, const rt_hit *h);

/* The floor report's recording hooks (tracer_floor.c). In the instrumented build (-DRT_TRACE, made by
 * bench/floor.py) they write the kind of the rays being traced, every scene query and every leaf solve whose ray
 * enters the leaf's box into the scene's log, if one is attached; otherwise they are empty, and the render loop
 * is the same code as without them. The kind is kept in the log: record with one render thread. */
#ifdef RT_TRACE
void rt_trace_set_kind(const rt_scene *s, int kind);
void rt_trace_query(const rt_scene *s, const double o[3], const double d[3], double tmin, double tmax, int mode,
                    int skip);
/* A leaf's solve along o + s u over [lo, hi] (in s) with the given mode (IG_ALL_ROOTS, IG_FIRST_ROOT, IG_ANY_ROOT,
 * or RT_TRACE_PLANE: the plane's own path, along the ray o + t d as it is), and the nr roots r it gave. */
void rt_trace_solve(const rt_scene *s, int leaf, const double o[3], const double u[3], double lo, double hi, int mode,
                    int nr, const double *r);
#define RT_TRACE_KIND(s, kind) rt_trace_set_kind((s), (kind))
#define RT_TRACE_QUERY(s, o, d, tmin, tmax, mode, skip) rt_trace_query((s), (o), (d), (tmin), (tmax), (mode), (skip))
#define RT_TRACE_SOLVE(s, leaf, o, u, lo, hi, mode, nr, r)                                                             \
    rt_trace_solve((s), (leaf), (o), (u), (lo), (hi), (mode), (nr), (r))
#else
#define RT_TRACE_KIND(s, kind) ((void)0)
#define RT_TRACE_QUERY(s, o, d, tmin, tmax, mode, skip) ((void)0)
#define RT_TRACE_SOLVE(s, leaf, o, u, lo, hi, mode, nr, r) ((void)0)
#endif
#define RT_TRACE_PLANE 3

/* tracer_scene.c */
void rt_xform_point(const double m[12], const double p[3], double out[3]);
void rt_xform_vector(const double m[12], const double v[3], double out[3]);
/* The ray in a leaf's object space (a copy when the leaf's transform is the identity). */
void rt_to_object(const rt_node *n, const double o[3], const double d[3], double oo[3], double od[3]);
/* tracer_hit.c */
int rt_scene_closest(const rt_scene *s, const double o[3], const double d[3], double tmin, double tmax, int mode,
                     int skip, rt_pending *out);
/* Fills hit (normal, object-space point, ...) for the pending hit of the ray o + t d. With lazy == NULL the
 * error bound hit->err too; otherwise hit->err is left for rt_hit_error, and lazy keeps what it needs. */
void rt_finish_hit(const rt_scene *s, const rt_pending *p, const double o[3], const double d[3], rt_hit *hit,
                   rt_hit_lazy *lazy);
/* Works out hit->err if rt_finish_hit left it pending (else does nothing): the same value either way. */
void rt_hit_error(const rt_scene *s, rt_hit *hit, rt_hit_lazy *lazy);

/* tracer_csg.c */
int rt_leaf_roots(const rt_node *n, const double oo[3], const double od[3], double lo, double hi, double *r);
int rt_spans(const rt_scene *s, int node, const rt_ray *ray, double a, double b, rt_span *out, int max);
/* The nearest hit of one top-level object with tmin < t < tmax: 1 and *hit filled, or 0. any != 0: a yes/no
 * query for an opaque shadow ray -- on an opaque top-level leaf the hit's t may be left unrefined (any point of
 * the certified piece that holds the root, see IG_ANY_ROOT), so only its existence may be used. */
int rt_object_hit(const rt_scene *s, int object, const rt_ray *ray, double tmin, double tmax, int any, rt_pending *hit);

/* Slab clipping of [*t0, *t1] against an axis-aligned box (sides may be infinite), given the ray's inverse
 * direction inv (any value on an axis where d is 0), or NULL to divide only on the axes reached. An empty or
 * NaN box, or a ray parallel to an axis and outside the box on it, gives 0. f0/f1 (may be NULL) receive the
 * outward face code +-(axis + 1) of the face that moved the bound, or keep their value when the bound did not
 * move. Returns 1 when the clipped interval is non-empty. */
static inline int rt_clip_slabs(const double box[6], const double o[3], const double d[3], const double inv[3],
                                double *t0, double *t1, int *f0, int *f1)
{
    double lo = *t0, hi = *t1;
    int a;
    for (a = 0; a < 3; ++a) {
        double bmin = box[a], bmax = box[a + 3], ta, tb;
        int fa;
        if (!(bmin <= bmax))
            return 0; /* empty or NaN box */
        if (d[a] == 0.0) {
            if (!(o[a] >= bmin && o[a] <= bmax))
                return 0;
            continue;
        }
        /* outward normal of the face the ray enters through: the min face, or the max one when d < 0 */
        fa = ig_slab(bmin, bmax, o[a], inv ? inv[a] : 1.0 / d[a], &ta, &tb) ? a + 1 : -(a + 1);
        if (ta > lo) {
            lo = ta;
            if (f0)
                *f0 = fa;
        }
        if (tb < hi) {
            hi = tb;
            if (f1)
                *f1 = -fa;
        }
        if (!(lo <= hi))
            return 0;
    }
    *t0 = lo;
    *t1 = hi;
    return 1;
}

/* small vector helpers */
static inline double rt_dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline double rt_maxabs3(const double v[3])
{
    double a = fabs(v[0]), b = fabs(v[1]), c = fabs(v[2]);
    return a > b ? (a > c ? a : c) : (b > c ? b : c);
}

/* The unit direction d / len of a ray of length len ((0, 0, 0) when len is 0) into u. */
static inline void rt_unit_of(const double d[3], double len, double u[3])
{
    int a;
    for (a = 0; a < 3; ++a)
        u[a] = len > 0.0 ? d[a] / len : 0.0;
}

/* The ray o + t d with its length, inverse direction, where an unbounded object's solve stops (far / |d|) and, when
 * unit (the scene's unit_rays), its unit direction. */
static inline void rt_ray_init(rt_ray *r, const double o[3], const double d[3], double far, int unit)
{
    int a;
    memcpy(r->o, o, sizeof r->o);
    memcpy(r->d, d, sizeof r->d);
    r->len = sqrt(rt_dot(d, d));
    for (a = 0; a < 3; ++a)
        r->inv[a] = d[a] != 0.0 ? 1.0 / d[a] : 0.0;
    r->unit = unit;
    if (unit)
        rt_unit_of(d, r->len, r->u);
    r->far_t = r->len > 0.0 ? far / r->len : INFINITY;
}

/* The ray's unit direction: its own when worked out, else into tmp (the same quotients). */
static inline const double *rt_ray_unit(const rt_ray *r, double tmp[3])
{
    if (r->unit)
        return r->u;
    rt_unit_of(r->d, r->len, tmp);
    return tmp;
}

static inline int rt_clip_box(const double box[6], const double o[3], const double d[3], double *t0, double *t1,
                              int *f0, int *f1)
{
    return rt_clip_slabs(box, o, d, NULL, t0, t1, f0, f1);
}

/* The solver's view of f at the root s of the expansion ex (degree deg; see shape.h): Horner's running error
 * sum |c_k| |tau|^k and the expansion's value at tau = s - ex->ts, the root's offset from the shift point. */
static inline void rt_expansion_noise(const ig_shape_expansion *ex, int deg, double s, double *sum, double *val)
{
    double tau = s - ex->ts, a = fabs(tau), su = 0.0, v = 0.0;
    int k;
    for (k = deg; k >= 0; --k) {
        su = su * a + fabs(ex->c[k]);
        v = v * tau + ex->c[k];
    }
    *sum = su;
    *val = v;
}

#endif
