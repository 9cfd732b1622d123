/* Generated shapes as Embree 3 user geometry: bounds, intersect and occluded callbacks (see embree_shape.h).
 *
 * A lane's ray (float in Embree) is taken as the doubles it holds, moved into the primitive's object space
 * (numerics.h's affine maps, as the tracer moves it) and solved along its unit object-space direction by
 * ig_shape_solve, the one ray/shape solve of the runtime (box clip, origin shift, certified first root): the
 * same steps as the tracer's top-level surfaces (tracer_csg.c), so both find the same roots. Each root in
 * [tnear, tfar] is offered to Embree's filters for this lane alone; a rejected one makes way for the next root.
 */
#include "embree_shape.h"
#include "numerics.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* Field k of lane i of an N-wide structure-of-arrays ray or hit (rtcore_ray.h's RTCRayN_* / RTCHitN_* layout,
 * which its C++-only accessors spell out): rays are org_x org_y org_z tnear dir_x dir_y dir_z time tfar mask id
 * flags, hits Ng_x Ng_y Ng_z u v primID geomID instID[levels]. */
enum { R_ORG = 0, R_TNEAR = 3, R_DIR = 4, R_TFAR = 8, R_MASK = 9, R_ID = 10, R_FIELDS = 12 };
enum { H_NG = 0, H_U = 3, H_V = 4, H_PRIM = 5, H_GEOM = 6, H_INST = 7, H_FIELDS = 7 + RTC_MAX_INSTANCE_LEVEL_COUNT };

static inline float *ray_f(void *ray, unsigned int N, int k, unsigned int i) { return (float *)ray + k * N + i; }
static inline unsigned int *ray_u(void *ray, unsigned int N, int k, unsigned int i)
{
    return (unsigned int *)ray + k * N + i;
}

#if defined(__GNUC__)
#define IG_ALIGNED __attribute__((aligned(64)))
#else
#define IG_ALIGNED
#endif

/* ------------------------------------------------------------------ primitives */

static double round_down(double x)
{
    float f = (float)x;
    return (double)f > x ? (double)nextafterf(f, -INFINITY) : (double)f;
}

static double round_up(double x)
{
    float f = (float)x;
    return (double)f < x ? (double)nextafterf(f, INFINITY) : (double)f;
}

int ig_embree_prim_init(ig_embree_prim *prim, const ig_shape *shape, const double *params,
                        const double *object_to_geometry)
{
    static const double eye[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    double obox[6] = {-INFINITY, -INFINITY, -INFINITY, INFINITY, INFINITY, INFINITY};
    int a, i;
    memset(prim, 0, sizeof *prim);
    if (!shape || !shape->coeffs || !shape->bounds || (shape->nparams > 0 && !params))
        return -1;
    memcpy(prim->m, object_to_geometry ? object_to_geometry : eye, sizeof prim->m);
    for (i = 0; i < 12; ++i)
        if (!isfinite(prim->m[i]))
            return -1;
    if (!ig_affine_invert(prim->m, prim->minv))
        return -1;
    prim->identity = memcmp(prim->m, eye, sizeof eye) == 0;
    if (!shape->bounds(params, obox))
        return -1;
    for (a = 0; a < 6; ++a)
        if (!isfinite(obox[a]))
            return -1;
    prim->shape = shape;
    prim->params = params;
    ig_shape_prepare(shape, params, &prim->prep);
    /* the box through m, padded, as the tracer's world boxes; the bounds callback rounds it outward to float */
    ig_affine_box(prim->m, obox, prim->box);
    return 0;
}

void ig_embree_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const ig_embree_shapes *g = (const ig_embree_shapes *)args->geometryUserPtr;
    const double *b = g->prims[args->primID].box;
    struct RTCBounds *o = args->bounds_o;
    o->lower_x = (float)round_down(b[0]);
    o->lower_y = (float)round_down(b[1]);
    o->lower_z = (float)round_down(b[2]);
    o->upper_x = (float)round_up(b[3]);
    o->upper_y = (float)round_up(b[4]);
    o->upper_z = (float)round_up(b[5]);
}

/* ------------------------------------------------------------------ one lane */

/* A lane's ray in the primitive's object space: origin oo and unit direction u, as the tracer moves it; returns
 * the length L of the object-space direction (the solve's parameter is s = t L), or 0 when it is not positive
 * and finite. */
static double lane_ray(const ig_embree_prim *p, const double o[3], const double d[3], double oo[3], double u[3])
{
    double L = ig_affine_unit_ray(p->identity ? NULL : p->minv, o, d, oo, u);
    return (L > 0.0 && isfinite(L)) ? L : 0.0;
}

/* The first root t of the lane's ray with lo <= t <= hi (lo excluded when open): 1, or 0. */
static int next_root(const ig_embree_prim *p, const double oo[3], const double u[3], double L, double lo, int open,
                     double hi, double *t)
{
    double s0 = lo * L, r[IG_MAX_DEGREE + 2];
    int nr, i;
    if (open)
        s0 = nextafter(s0, INFINITY);
    if (!(s0 <= hi * L))
        return 0;
    nr = ig_shape_solve(p->shape, p->params, &p->prep, oo, u, s0, hi * L, IG_ROOTS_AUTO, 1, r, NULL);
    for (i = 0; i < nr; ++i) {
        double x = r[i] / L;
        if (x >= lo && x <= hi && (!open || x > lo)) {
            *t = x;
            return 1;
        }
    }
    return 0;
}

/* The unit normal at the lane's hit in the geometry's space (grad f through m's inverse transpose, as the
 * tracer's), in double; facing the ray where grad f vanishes (a cone's apex). */
static void hit_normal(const ig_embree_prim *p, const double oo[3], const double u[3], double L, double t,
                       const double d[3], double n[3])
{
    double po[3], no[3], len;
    int i;
    for (i = 0; i < 3; ++i)
        po[i] = oo[i] + (t * L) * u[i];
    if (ig_shape_normal(p->shape, p->params, po, no) && ig_affine_normal(p->minv, no, n))
        return;
    len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (i = 0; i < 3; ++i)
        n[i] = -d[i] / len;
}

static void lane_in(void *ray, unsigned int N, unsigned int i, double o[3], double d[3])
{
    int k;
    for (k = 0; k < 3; ++k) {
        o[k] = *ray_f(ray, N, R_ORG + k, i);
        d[k] = *ray_f(ray, N, R_DIR + k, i);
    }
}

/* The double record of ray lane i, when the context carries one. */
static ig_embree_hit *record(const ig_embree_shapes *g, struct RTCIntersectContext *ctx, void *ray, unsigned int N,
                             unsigned int i)
{
    ig_embree_context *c = (ig_embree_context *)ctx;
    unsigned int id;
    if (!g->double_hits || !c->hits)
        return NULL;
    id = *ray_u(ray, N, R_ID, i);
    return id < c->nhits ? &c->hits[id] : NULL;
}

/* A candidate hit in lane i of an N-wide hit buffer: every field of the lane, so nothing else of the buffer
 * needs clearing (filters read only the valid lane). */
static void put_hit(void *hit, unsigned int N, unsigned int i, const double n[3], unsigned int primID,
                    unsigned int geomID, const unsigned int *instID)
{
    int k;
    for (k = 0; k < 3; ++k)
        *ray_f(hit, N, H_NG + k, i) = (float)n[k];
    *ray_f(hit, N, H_U, i) = 0.0f;
    *ray_f(hit, N, H_V, i) = 0.0f;
    *ray_u(hit, N, H_PRIM, i) = primID;
    *ray_u(hit, N, H_GEOM, i) = geomID;
    for (k = 0; k < RTC_MAX_INSTANCE_LEVEL_COUNT; ++k)
        *ray_u(hit, N, H_INST + k, i) = instID[k];
}

/* A candidate hit per lane and the arguments that hand it to Embree's filters (rtcFilterIntersection,
   rtcFilterOcclusion): every lane off until the lane being tried is switched on. */
typedef struct {
    union {
        float f;
        unsigned int u;
    } cand[IG_EMBREE_MAX_N * H_FIELDS] IG_ALIGNED;
    int fvalid[IG_EMBREE_MAX_N] IG_ALIGNED;
    struct RTCFilterFunctionNArguments fa;
} filter_call;

static int filter_begin(filter_call *fc, void *geometryUserPtr, struct RTCIntersectContext *context, void *ray,
                        unsigned int N)
{
    if (N > IG_EMBREE_MAX_N)
        return 0;
    /* only the N lanes in use: a lane's candidate is written whole before it is switched on (put_hit) */
    memset(fc->fvalid, 0, N * sizeof fc->fvalid[0]);
    fc->fa.valid = fc->fvalid;
    fc->fa.geometryUserPtr = geometryUserPtr;
    fc->fa.context = context;
    fc->fa.ray = (struct RTCRayN *)ray;
    fc->fa.hit = (struct RTCHitN *)fc->cand;
    fc->fa.N = N;
    return 1;
}

/* ------------------------------------------------------------------ the callbacks */

/* One callback's query: its filter call, what it hands to rtcFilterIntersection or rtcFilterOcclusion, and the
 * primitive it solves. */
typedef struct {
    filter_call fc;
    const void *args; /* the callback's RTCIntersectFunctionNArguments or RTCOccludedFunctionNArguments */
    int occlusion;
    const ig_embree_prim *prim;
    unsigned int primID, geomID;
} lane_query;

/* The core both callbacks share: the first root t of lane i's ray in [tnear, hi] that the filters accept, tried
 * root by root (up to the degree; a rejected root makes way for the next one along the ray). Returns 1 with t,
 * its unit normal n in double, the lane's tfar = t rounded to float and its accepted candidate (hit fields) in q->fc.cand; 0 with tfar as it
 * was. */
static int next_accepted_root(lane_query *q, void *ray, unsigned int N, unsigned int i, double hi, double *t,
                              double n[3])
{
    const ig_embree_prim *p = q->prim;
    double o[3], d[3], oo[3], u[3], L, lo;
    float *tfar = ray_f(ray, N, R_TFAR, i);
    int open = 0, tries;
    lane_in(ray, N, i, o, d);
    lo = *ray_f(ray, N, R_TNEAR, i);
    L = lane_ray(p, o, d, oo, u);
    if (!(L > 0.0) || !(lo <= hi))
        return 0;
    for (tries = 0; tries <= p->prep.degree && next_root(p, oo, u, L, lo, open, hi, t); ++tries) {
        float old = *tfar;
        hit_normal(p, oo, u, L, *t, d, n);
        put_hit(q->fc.cand, N, i, n, q->primID, q->geomID, q->fc.fa.context->instID);
        q->fc.fvalid[i] = -1;
        *tfar = (float)*t;
        if (q->occlusion)
            rtcFilterOcclusion((const struct RTCOccludedFunctionNArguments *)q->args, &q->fc.fa);
        else
            rtcFilterIntersection((const struct RTCIntersectFunctionNArguments *)q->args, &q->fc.fa);
        if (q->fc.fvalid[i] != 0) {
            q->fc.fvalid[i] = 0;
            return 1;
        }
        *tfar = old;
        lo = *t;
        open = 1;
    }
    return 0;
}

void ig_embree_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    const ig_embree_shapes *g = (const ig_embree_shapes *)args->geometryUserPtr;
    unsigned int N = args->N, i, k;
    void *ray = args->rayhit, *hits = (float *)args->rayhit + R_FIELDS * N;
    lane_query q;
    if (!filter_begin(&q.fc, args->geometryUserPtr, args->context, ray, N))
        return;
    q.args = args;
    q.occlusion = 0;
    q.prim = &g->prims[args->primID];
    q.primID = args->primID;
    q.geomID = args->geomID;
    for (i = 0; i < N; ++i) {
        ig_embree_hit *rec;
        double hi, t, n[3];
        if (args->valid[i] == 0) /* an inactive lane is never read nor written */
            continue;
        hi = *ray_f(ray, N, R_TFAR, i);
        rec = record(g, args->context, ray, N, i);
        /* the current hit is one of ours: its double distance orders the surfaces, not the float tfar */
        if (rec && rec->geomID == *ray_u(hits, N, H_GEOM, i) && rec->primID == *ray_u(hits, N, H_PRIM, i) &&
            rec->instID == *ray_u(hits, N, H_INST, i) && rec->t < hi)
            hi = rec->t;
        if (!next_accepted_root(&q, ray, N, i, hi, &t, n))
            continue;
        for (k = 0; k < H_FIELDS; ++k)
            *ray_u(hits, N, (int)k, i) = q.fc.cand[k * N + i].u;
        if (rec) {
            rec->t = t;
            memcpy(rec->n, n, sizeof rec->n);
            rec->geomID = args->geomID;
            rec->primID = args->primID;
            rec->instID = args->context->instID[0];
        }
    }
}

void ig_embree_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    const ig_embree_shapes *g = (const ig_embree_shapes *)args->geometryUserPtr;
    unsigned int N = args->N, i;
    lane_query q;
    if (!filter_begin(&q.fc, args->geometryUserPtr, args->context, args->ray, N))
        return;
    q.args = args;
    q.occlusion = 1;
    q.prim = &g->prims[args->primID];
    q.primID = args->primID;
    q.geomID = args->geomID;
    for (i = 0; i < N; ++i) {
        double t, n[3];
        if (args->valid[i] != 0 && next_accepted_root(&q, args->ray, N, i, *ray_f(args->ray, N, R_TFAR, i), &t, n))
            *ray_f(args->ray, N, R_TFAR, i) = -INFINITY; /* Embree's mark of an occluded ray */
    }
}

RTCGeometry ig_embree_new_geometry(RTCDevice device, const ig_embree_shapes *shapes)
{
    RTCGeometry geom;
    if (!device || !shapes || !shapes->prims || shapes->count == 0)
        return NULL;
    geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    if (!geom)
        return NULL;
    rtcSetGeometryUserPrimitiveCount(geom, shapes->count);
    rtcSetGeometryUserData(geom, (void *)shapes);
    rtcSetGeometryBoundsFunction(geom, ig_embree_bounds, NULL);
    rtcSetGeometryIntersectFunction(geom, ig_embree_intersect);
    rtcSetGeometryOccludedFunction(geom, ig_embree_occluded);
    return geom;
}

/* ------------------------------------------------------------------ double-precision records */

void ig_embree_context_init(ig_embree_context *ctx, ig_embree_hit *hits, unsigned int nhits)
{
    unsigned int i;
    rtcInitIntersectContext(&ctx->rtc);
    ctx->hits = hits;
    ctx->nhits = hits ? nhits : 0;
    for (i = 0; i < ctx->nhits; ++i) {
        memset(&hits[i], 0, sizeof hits[i]);
        hits[i].t = INFINITY;
        hits[i].geomID = hits[i].primID = hits[i].instID = RTC_INVALID_GEOMETRY_ID;
    }
}

int ig_embree_double_t(const ig_embree_context *ctx, unsigned int id, unsigned int geomID, unsigned int primID,
                       unsigned int instID, double *t)
{
    const ig_embree_hit *h;
    if (!ctx->hits || id >= ctx->nhits || geomID == RTC_INVALID_GEOMETRY_ID)
        return 0;
    h = &ctx->hits[id];
    if (h->geomID != geomID || h->primID != primID || h->instID != instID)
        return 0;
    *t = h->t;
    return 1;
}
