/* Generated algebraic shapes as Embree 3 user geometry: the adapter, written once for every shape.
 *
 * Any `ig_shape` that implgen generates (`<name>_shape` in <name>.c) becomes a primitive of an Embree user
 * geometry: ig_embree_prim_init gives it its params and a transform into the geometry's space,
 * ig_embree_new_geometry makes the RTCGeometry with the three callbacks below. The rays Embree hands over are
 * solved as the tracer solves a top-level surface (runtime_c/shape.c: the spec's box clips the ray, f is
 * expanded at a shifted origin next to the object, the certified solver finds the first root), in double.
 *
 * What a hit reports (lane i of the packet): tfar = t rounded to float, Ng = the unit outward normal
 * grad f / |grad f| in the geometry's space (world, or the instance's space when the geometry sits in an
 * instanced scene: Embree leaves normals of instanced geometry in that space), u = v = 0 (a surface has no
 * parametrisation), primID = the primitive's index, geomID = the geometry's id, instID[0] = the instance the
 * ray is in (RTC_INVALID_GEOMETRY_ID outside any). Every candidate hit first goes through rtcFilterIntersection /
 * rtcFilterOcclusion, so a geometry's or a context's filter function sees it (and may reject it: the next root
 * along the ray is tried); Embree itself applies ray masks before calling the callbacks. An occluded ray gets
 * tfar = -inf, as Embree expects. Valid hits lie in [tnear, tfar].
 *
 * Embree's rays are float; the solve is double. A caller that wants the double-precision distance passes an
 * ig_embree_context (an RTCIntersectContext extended with a table of ig_embree_hit indexed by the ray's `id`
 * field) and sets `double_hits` in ig_embree_shapes. Nothing here has global state; the callbacks only read the
 * primitives, so any number of threads may trace at once.
 *
 * Embree 4 (docs/embree.md#embree-4): RTCIntersectContext becomes RTCRayQueryContext (passed inside
 * RTCIntersectArguments), rtcFilterIntersection / rtcFilterOcclusion become rtcInvokeIntersectFilterFromGeometry /
 * rtcInvokeOccludedFilterFromGeometry, and the double-hit table moves into an extended RTCRayQueryContext. */
#ifndef IMPLGEN_EMBREE_SHAPE_H
#define IMPLGEN_EMBREE_SHAPE_H

#include <embree3/rtcore.h>

#include "shape.h"

/* The widest packet the callbacks accept: Embree 3 calls user geometry with N = 1, 4, 8 or 16. */
#define IG_EMBREE_MAX_N 16

/* One algebraic primitive: a shape, its params and where it stands. Filled by ig_embree_prim_init. */
typedef struct ig_embree_prim {
    const ig_shape *shape;
    const double *params; /* shape->nparams values in declared order; not copied: must outlive the geometry */
    double m[12];         /* object -> geometry space, row-major 3x4 as in tracer.h */
    double minv[12];      /* geometry -> object space */
    int identity;         /* m is exactly the identity: rays are solved as given */
    double box[6];        /* the spec's box through m (its 8 corners), padded: what the bounds callback gives */
    ig_shape_prep prep;   /* shape.c's clip and shift data for shape + params */
} ig_embree_prim;

/* object_to_geometry: 12 doubles (NULL: the identity). Returns 0, or -1 when the shape has no box finite on
 * every axis (Embree needs finite bounds: clip an unbounded shape with a box in its spec) or when the
 * transform is not finite and invertible. */
int ig_embree_prim_init(ig_embree_prim *prim, const ig_shape *shape, const double *params,
                        const double *object_to_geometry);

/* What the geometry's user data points to. Must outlive the geometry. */
typedef struct ig_embree_shapes {
    const ig_embree_prim *prims;
    unsigned int count;
    int double_hits; /* 1: every context given to rtcIntersect* / rtcOccluded* with this geometry in the scene
                        is an ig_embree_context (its hits table may still be NULL) */
} ig_embree_shapes;

/* A user geometry of shapes->count primitives with the callbacks below, not yet committed (set a mask or a
 * filter function first if you want them, then rtcCommitGeometry and rtcAttachGeometry). NULL on error. */
RTCGeometry ig_embree_new_geometry(RTCDevice device, const ig_embree_shapes *shapes);

/* The callbacks, for a caller that builds its own user geometry (user data: an ig_embree_shapes). */
void ig_embree_bounds(const struct RTCBoundsFunctionArguments *args);
void ig_embree_intersect(const struct RTCIntersectFunctionNArguments *args);
void ig_embree_occluded(const struct RTCOccludedFunctionNArguments *args);

/* ---- double-precision hits (optional) ---- */
typedef struct ig_embree_hit {
    double t;    /* the accepted hit's distance, before rounding to float */
    double n[3]; /* its unit normal, in double (as Ng) */
    unsigned int geomID, primID, instID;
} ig_embree_hit;

typedef struct ig_embree_context {
    struct RTCIntersectContext rtc; /* first: pass &ctx.rtc to Embree */
    ig_embree_hit *hits;            /* NULL, or hits[id] for every ray whose id field is < nhits */
    unsigned int nhits;
} ig_embree_context;

/* rtcInitIntersectContext, and every record cleared (t = INFINITY, ids RTC_INVALID_GEOMETRY_ID). */
void ig_embree_context_init(ig_embree_context *ctx, ig_embree_hit *hits, unsigned int nhits);

/* After the query: 1 and *t the double distance when the ray's final hit (its geomID, primID, instID) is the
 * algebraic hit recorded for ray `id`; 0 when the final hit is something else (a triangle: use its tfar). */
int ig_embree_double_t(const ig_embree_context *ctx, unsigned int id, unsigned int geomID, unsigned int primID,
                       unsigned int instID, double *t);

#endif
