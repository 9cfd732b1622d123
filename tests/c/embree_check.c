/* The Embree adapter (runtime_c/embree_shape.c) against implgen's own tracer, ray by ray, on one scene file.
 * Built by tests/test_embree.py (ASan + UBSan) and bench/embree.py (-O2), linked with the runtime, the
 * generated shapes below and -lembree3.
 *
 *   embree_check MODE SCENE W H [ARG]
 *
 * SCENE is text: `camera ex ey ez lx ly lz ux uy uz fov`, `light x y z`, `ground HALF` (Embree: two triangles;
 * tracer: the plane y = 0 clipped to the same square), `mesh NTRI` (Embree only: a sphere of about NTRI
 * triangles, radius 0.5, at the origin), `obj NAME params... m[12]` (a generated shape, object -> world).
 * Objects are numbered in file order, the ground after them. Camera rays are rounded to float, and both
 * tracers get those same rays. MODE:
 *   agree OUT inst   per pixel, into OUT: ray, tracer object and t, Embree object and t, and a shadow ray's
 *                    answers (occluded or not); inst = 1 places the shapes by Embree instances (float)
 *                    instead of the adapter's double transforms
 *   packets [K]      rtcIntersect4/8/16 and rtcOccluded4/8/16, some lanes invalid, against rtcIntersect1 (with
 *                    K: all through a context filter that rejects object K)
 *   surface          rays leaving the tracer's hit points (tnear = 1e-4) through both
 *   masks            geometry masks: algebraic 2, ground 1; rays of mask 1, 2, 3 against tracers without the rest
 *   filter K         context, geometry and occlusion filters that reject object K against a tracer without K
 *   threads T        T threads tracing the camera rays at once (each its own double-hit table) against one
 *   bench REPS       rays/s of the tracer and of Embree (1 and 8 wide), primary and shadow rays, one thread
 * Prints one summary line per check; exit status 1 when a check fails.
 */
#define _POSIX_C_SOURCE 199309L /* clock_gettime */
#include "embree_shape.h"
#include "plane_y.h"
#include "tracer.h"

#include "blobs10.h"
#include "chmutov8.h"
#include "heart.h"
#include "piriform.h"
#include "sphere.h"
#include "torus_y.h"
#include "torus_z.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAXP 8
static const ig_shape *const SHAPES[] = {&blobs10_shape, &chmutov8_shape, &heart_shape,  &piriform_shape,
                                         &sphere_shape,  &torus_y_shape,  &torus_z_shape};

/* the ground of the tracer: the plane y = 0 (plane_y.h), clipped to |x|, |z| <= params[0] */
static int plane_bounds(const double *p, double box[6])
{
    box[0] = box[2] = -p[0];
    box[3] = box[5] = p[0];
    box[1] = -1.0;
    box[4] = 1.0;
    return 1;
}
static const ig_shape plane_shape = {"ground", 1, 1, plane_y_coeffs, plane_y_value, plane_y_gradient, plane_bounds, 0};

typedef struct scene_in {
    double eye[3], look[3], up[3], fov, light[3], ground;
    int mesh, n, cap;
    const ig_shape **shape;
    double *params, *m;
} scene_in;

static int fail(const char *what)
{
    fprintf(stderr, "embree_check: %s\n", what);
    exit(2);
}

static void read_scene(const char *path, scene_in *s)
{
    FILE *f = fopen(path, "r");
    char word[64];
    int i, k;
    memset(s, 0, sizeof *s);
    if (!f)
        fail("cannot open the scene");
    while (fscanf(f, "%63s", word) == 1) {
        if (!strcmp(word, "camera")) {
            for (i = 0; i < 3; ++i)
                k = fscanf(f, "%lf", &s->eye[i]);
            for (i = 0; i < 3; ++i)
                k = fscanf(f, "%lf", &s->look[i]);
            for (i = 0; i < 3; ++i)
                k = fscanf(f, "%lf", &s->up[i]);
            k = fscanf(f, "%lf", &s->fov);
        } else if (!strcmp(word, "light")) {
            for (i = 0; i < 3; ++i)
                k = fscanf(f, "%lf", &s->light[i]);
        } else if (!strcmp(word, "ground")) {
            k = fscanf(f, "%lf", &s->ground);
        } else if (!strcmp(word, "mesh")) {
            k = fscanf(f, "%d", &s->mesh);
        } else if (!strcmp(word, "obj")) {
            const ig_shape *sh = NULL;
            if (fscanf(f, "%63s", word) != 1)
                fail("obj without a name");
            for (i = 0; i < (int)(sizeof SHAPES / sizeof SHAPES[0]); ++i)
                if (!strcmp(SHAPES[i]->name, word))
                    sh = SHAPES[i];
            if (!sh || sh->nparams > MAXP)
                fail("unknown shape");
            if (s->n == s->cap) {
                s->cap = s->cap ? 2 * s->cap : 16;
                s->shape = realloc(s->shape, (size_t)s->cap * sizeof *s->shape);
                s->params = realloc(s->params, (size_t)s->cap * MAXP * sizeof(double));
                s->m = realloc(s->m, (size_t)s->cap * 12 * sizeof(double));
                if (!s->shape || !s->params || !s->m)
                    fail("out of memory");
            }
            s->shape[s->n] = sh;
            for (i = 0; i < sh->nparams; ++i)
                if (fscanf(f, "%lf", &s->params[s->n * MAXP + i]) != 1)
                    fail("bad params");
            for (i = 0; i < 12; ++i)
                if (fscanf(f, "%lf", &s->m[s->n * 12 + i]) != 1)
                    fail("bad matrix");
            s->n++;
        } else {
            fail("unknown line");
        }
        (void)k;
    }
    fclose(f);
}

/* ------------------------------------------------------------------ the two scenes */

static rt_scene *tracer_scene(const scene_in *s, int skip, int objects, int ground)
{
    double mat[RT_MATERIAL_DOUBLES] = {0.8, 0.8, 0.8, 0, 0, 0, 0, 0.1, 0.9, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0};
    static const double eye12[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    rt_scene *t = rt_scene_new();
    int mi = rt_scene_add_material(t, mat), i;
    for (i = 0; objects && i < s->n; ++i)
        if (i != skip)
            rt_scene_add_object(
                t, rt_scene_add_leaf(t, s->shape[i], &s->params[i * MAXP], s->shape[i]->nparams, &s->m[i * 12], mi));
    if (ground && s->ground > 0)
        rt_scene_add_object(t, rt_scene_add_leaf(t, &plane_shape, &s->ground, 1, eye12, mi));
    if (rt_scene_commit(t) != 0)
        fail(rt_scene_error(t));
    return t;
}

/* tracer object index (as in tracer_scene with skip) -> scene object number */
static int tracer_object(const scene_in *s, int skip, int objects, int k)
{
    int n = objects ? s->n - (skip >= 0) : 0;
    if (k < n)
        return (skip >= 0 && k >= skip) ? k + 1 : k;
    return s->n; /* the ground */
}

typedef struct emb {
    RTCDevice dev;
    RTCScene scene;
    ig_embree_prim *prims;
    ig_embree_shapes shapes;
    RTCScene *children; /* instance mode: one scene per object */
    ig_embree_shapes *child_shapes;
    unsigned alg_geom, ground_geom, mesh_geom;
    int inst;
} emb;

static unsigned add_triangles(emb *e, const float *v, int nv, const unsigned *ix, int nt)
{
    RTCGeometry g = rtcNewGeometry(e->dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt);
    unsigned id;
    memcpy(vb, v, 3 * sizeof(float) * (size_t)nv);
    memcpy(ib, ix, 3 * sizeof(unsigned) * (size_t)nt);
    rtcSetGeometryMask(g, 1);
    rtcCommitGeometry(g);
    id = rtcAttachGeometry(e->scene, g);
    rtcReleaseGeometry(g);
    return id;
}

/* a UV sphere of about ntri triangles, radius 0.5 at the origin */
static unsigned add_mesh(emb *e, int ntri)
{
    int rings = (int)sqrt(ntri / 2.0) + 2, segs = rings, nv = (rings + 1) * segs, nt = 2 * rings * segs, i, j, k = 0;
    float *v = malloc(sizeof(float) * 3 * (size_t)nv);
    unsigned *ix = malloc(sizeof(unsigned) * 3 * (size_t)nt), id;
    if (!v || !ix)
        fail("out of memory");
    for (i = 0; i <= rings; ++i)
        for (j = 0; j < segs; ++j) {
            double th = 3.14159265358979 * i / rings, ph = 2 * 3.14159265358979 * j / segs;
            v[3 * (i * segs + j)] = (float)(0.5 * sin(th) * cos(ph));
            v[3 * (i * segs + j) + 1] = (float)(0.5 * cos(th));
            v[3 * (i * segs + j) + 2] = (float)(0.5 * sin(th) * sin(ph));
        }
    for (i = 0; i < rings; ++i)
        for (j = 0; j < segs; ++j) {
            unsigned a = (unsigned)(i * segs + j), b = (unsigned)(i * segs + (j + 1) % segs);
            unsigned c = a + (unsigned)segs, d = b + (unsigned)segs;
            ix[k++] = a, ix[k++] = c, ix[k++] = b;
            ix[k++] = b, ix[k++] = c, ix[k++] = d;
        }
    id = add_triangles(e, v, nv, ix, nt);
    free(v);
    free(ix);
    return id;
}

static void embree_scene(const scene_in *s, emb *e, int inst, enum RTCSceneFlags flags)
{
    int i;
    memset(e, 0, sizeof *e);
    e->inst = inst;
    e->dev = rtcNewDevice(getenv("IG_EMBREE_CONFIG")); /* e.g. "isa=avx2": every ISA on one machine */
    e->scene = rtcNewScene(e->dev);
    rtcSetSceneFlags(e->scene, flags); /* before the first commit: Embree picks its traversal kernels there */
    e->prims = calloc((size_t)s->n + 1, sizeof *e->prims);
    if (!e->dev || !e->scene || !e->prims)
        fail("cannot start Embree");
    e->alg_geom = e->ground_geom = e->mesh_geom = RTC_INVALID_GEOMETRY_ID;
    if (!inst && s->n > 0) {
        for (i = 0; i < s->n; ++i)
            if (ig_embree_prim_init(&e->prims[i], s->shape[i], &s->params[i * MAXP], &s->m[i * 12]) != 0)
                fail("prim init");
        e->shapes.prims = e->prims;
        e->shapes.count = (unsigned)s->n;
        e->shapes.double_hits = 1;
        RTCGeometry g = ig_embree_new_geometry(e->dev, &e->shapes);
        rtcSetGeometryMask(g, 2);
        rtcCommitGeometry(g);
        e->alg_geom = rtcAttachGeometry(e->scene, g);
        rtcReleaseGeometry(g);
    } else if (inst) {
        e->children = calloc((size_t)s->n + 1, sizeof *e->children);
        e->child_shapes = calloc((size_t)s->n + 1, sizeof *e->child_shapes);
        if (!e->children || !e->child_shapes)
            fail("out of memory");
        for (i = 0; i < s->n; ++i) {
            float m[12];
            int k;
            if (ig_embree_prim_init(&e->prims[i], s->shape[i], &s->params[i * MAXP], NULL) != 0)
                fail("prim init");
            e->child_shapes[i].prims = &e->prims[i];
            e->child_shapes[i].count = 1;
            e->child_shapes[i].double_hits = 1;
            e->children[i] = rtcNewScene(e->dev);
            RTCGeometry g = ig_embree_new_geometry(e->dev, &e->child_shapes[i]);
            rtcCommitGeometry(g);
            rtcAttachGeometry(e->children[i], g);
            rtcReleaseGeometry(g);
            rtcCommitScene(e->children[i]);
            for (k = 0; k < 12; ++k)
                m[k] = (float)s->m[i * 12 + k];
            g = rtcNewGeometry(e->dev, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(g, e->children[i]);
            rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m);
            rtcSetGeometryMask(g, 2);
            rtcCommitGeometry(g);
            if (rtcAttachGeometry(e->scene, g) != (unsigned)i)
                fail("instance ids");
            rtcReleaseGeometry(g);
        }
    }
    if (s->ground > 0) {
        float h = (float)s->ground, quad[12] = {-h, 0, -h, h, 0, -h, h, 0, h, -h, 0, h};
        const unsigned tri[6] = {0, 2, 1, 0, 3, 2};
        if ((double)h != s->ground)
            fail("ground half size must be a float");
        e->ground_geom = add_triangles(e, quad, 4, tri, 2);
    }
    if (s->mesh > 0)
        e->mesh_geom = add_mesh(e, s->mesh);
    rtcCommitScene(e->scene);
    if (rtcGetDeviceError(e->dev) != RTC_ERROR_NONE)
        fail("Embree error while building");
}

static void embree_free(const scene_in *s, emb *e)
{
    int i;
    rtcReleaseScene(e->scene);
    for (i = 0; e->children && i < s->n; ++i)
        rtcReleaseScene(e->children[i]);
    rtcReleaseDevice(e->dev);
    free(e->children);
    free(e->child_shapes);
    free(e->prims);
}

/* Embree hit -> scene object number (s->n: the ground; s->n + 1: the mesh; -1: none) */
static int embree_object(const scene_in *s, const emb *e, unsigned geomID, unsigned primID, unsigned instID)
{
    if (geomID == RTC_INVALID_GEOMETRY_ID)
        return -1;
    if (e->inst && instID != RTC_INVALID_GEOMETRY_ID)
        return (int)instID;
    if (!e->inst && geomID == e->alg_geom)
        return (int)primID;
    if (geomID == e->ground_geom)
        return s->n;
    return s->n + 1;
}

/* ------------------------------------------------------------------ rays */

static void camera_ray(const scene_in *s, int W, int H, int px, int py, float o[3], float d[3])
{
    double f[3], r[3], u[3], len, th = tan(0.5 * s->fov * 3.14159265358979323846 / 180.0), sx, sy;
    int i;
    for (i = 0; i < 3; ++i)
        f[i] = s->look[i] - s->eye[i];
    len = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (i = 0; i < 3; ++i)
        f[i] /= len;
    r[0] = f[1] * s->up[2] - f[2] * s->up[1];
    r[1] = f[2] * s->up[0] - f[0] * s->up[2];
    r[2] = f[0] * s->up[1] - f[1] * s->up[0];
    len = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (i = 0; i < 3; ++i)
        r[i] /= len;
    u[0] = r[1] * f[2] - r[2] * f[1];
    u[1] = r[2] * f[0] - r[0] * f[2];
    u[2] = r[0] * f[1] - r[1] * f[0];
    sx = (2.0 * (px + 0.5) / W - 1.0) * th * W / H;
    sy = (1.0 - 2.0 * (py + 0.5) / H) * th;
    for (i = 0; i < 3; ++i) {
        o[i] = (float)s->eye[i];
        d[i] = (float)(f[i] + sx * r[i] + sy * u[i]);
    }
}

static void set_ray(struct RTCRay *r, const float o[3], const float d[3], float tnear, float tfar, unsigned mask,
                    unsigned id)
{
    r->org_x = o[0], r->org_y = o[1], r->org_z = o[2], r->tnear = tnear;
    r->dir_x = d[0], r->dir_y = d[1], r->dir_z = d[2], r->time = 0.0f;
    r->tfar = tfar, r->mask = mask, r->id = id, r->flags = 0;
}

typedef struct answer {
    int obj;
    double t;
} answer;

static answer embree_closest(const scene_in *s, const emb *e, const float o[3], const float d[3], float tnear,
                             unsigned mask, RTCFilterFunctionN filter)
{
    ig_embree_hit rec;
    ig_embree_context ctx;
    struct RTCRayHit rh;
    answer a = {-1, INFINITY};
    double t;
    ig_embree_context_init(&ctx, &rec, 1);
    ctx.rtc.filter = filter;
    set_ray(&rh.ray, o, d, tnear, INFINITY, mask, 0);
    rh.hit.geomID = rh.hit.primID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(e->scene, &ctx.rtc, &rh);
    a.obj = embree_object(s, e, rh.hit.geomID, rh.hit.primID, rh.hit.instID[0]);
    if (a.obj >= 0)
        a.t = ig_embree_double_t(&ctx, 0, rh.hit.geomID, rh.hit.primID, rh.hit.instID[0], &t) ? t : rh.ray.tfar;
    return a;
}

static int embree_occluded(const emb *e, const float o[3], const float d[3], unsigned mask, RTCFilterFunctionN filter)
{
    ig_embree_context ctx;
    struct RTCRay r;
    ig_embree_context_init(&ctx, NULL, 0);
    ctx.rtc.filter = filter;
    set_ray(&r, o, d, 0.0f, 1.0f, mask, 0);
    rtcOccluded1(e->scene, &ctx.rtc, &r);
    return r.tfar < 0.0f;
}

static answer tracer_closest(const scene_in *s, const rt_scene *t, int skip, int objects, const float o[3],
                             const float d[3], double tmin, rt_hit *h)
{
    double od[3] = {o[0], o[1], o[2]}, dd[3] = {d[0], d[1], d[2]};
    answer a = {-1, INFINITY};
    if (rt_scene_intersect(t, od, dd, tmin, INFINITY, h)) {
        a.obj = tracer_object(s, skip, objects, h->object);
        a.t = h->t;
    }
    return a;
}

static int tracer_occluded(const rt_scene *t, const float o[3], const float d[3])
{
    double od[3] = {o[0], o[1], o[2]}, dd[3] = {d[0], d[1], d[2]};
    rt_hit h;
    return rt_scene_intersect(t, od, dd, 0.0, 1.0, &h);
}

/* the shadow ray of a tracer hit toward the light, in float (both tracers get it) */
static void shadow_ray(const scene_in *s, const rt_hit *h, float so[3], float sd[3])
{
    double dir[3], org[3];
    int i;
    for (i = 0; i < 3; ++i)
        dir[i] = s->light[i] - h->p[i];
    rt_spawn_origin(h, dir, org);
    for (i = 0; i < 3; ++i) {
        so[i] = (float)org[i];
        sd[i] = (float)(s->light[i] - (double)so[i]);
    }
}

/* ------------------------------------------------------------------ modes */

static int mode_agree(const scene_in *s, int W, int H, const char *out, int inst)
{
    rt_scene *t = tracer_scene(s, -1, 1, 1);
    emb e;
    size_t n = (size_t)W * H, k;
    float *ray = malloc(n * 12 * sizeof(float));
    int *ids = malloc(n * 4 * sizeof(int));
    double *ts = malloc(n * 2 * sizeof(double));
    FILE *f;
    if (!ray || !ids || !ts)
        fail("out of memory");
    embree_scene(s, &e, inst, RTC_SCENE_FLAG_NONE);
    for (k = 0; k < n; ++k) {
        float *o = ray + 12 * k, *d = o + 3, *so = o + 6, *sd = o + 9;
        rt_hit h;
        answer a, b;
        camera_ray(s, W, H, (int)(k % (size_t)W), (int)(k / (size_t)W), o, d);
        a = tracer_closest(s, t, -1, 1, o, d, 0.0, &h);
        b = embree_closest(s, &e, o, d, 0.0f, ~0u, NULL);
        ids[4 * k] = a.obj, ids[4 * k + 1] = b.obj;
        ts[2 * k] = a.t, ts[2 * k + 1] = b.t;
        ids[4 * k + 2] = ids[4 * k + 3] = -1;
        memset(so, 0, 6 * sizeof(float));
        if (a.obj >= 0) {
            shadow_ray(s, &h, so, sd);
            ids[4 * k + 2] = tracer_occluded(t, so, sd);
            ids[4 * k + 3] = embree_occluded(&e, so, sd, ~0u, NULL);
        }
    }
    f = fopen(out, "wb");
    if (!f || fwrite(ray, sizeof(float), 12 * n, f) != 12 * n || fwrite(ids, sizeof(int), 4 * n, f) != 4 * n ||
        fwrite(ts, sizeof(double), 2 * n, f) != 2 * n || fclose(f) != 0)
        fail("cannot write the answers");
    printf("agree: %zu pixels written\n", n);
    free(ray);
    free(ids);
    free(ts);
    embree_free(s, &e);
    rt_scene_free(t);
    return 0;
}

/* Field k of lane i in an N-wide SoA ray/hit (as embree_shape.c reads them). */
#define LANE_F(base, N, k, i) (((float *)(base))[(k) * (N) + (i)])
#define LANE_U(base, N, k, i) (((unsigned *)(base))[(k) * (N) + (i)])

/* Filters that reject every hit on scene object `reject_k` (a geometry user pointer cannot say which scene it
 * is, so the object to reject travels in a global-free way: the primID, compared with a value in the context). */
typedef struct reject_context {
    ig_embree_context ig; /* first: the adapter reads its hits table */
    unsigned prim;
    int calls;
} reject_context;

static void reject_prim(const struct RTCFilterFunctionNArguments *args)
{
    reject_context *c = (reject_context *)args->context;
    unsigned i;
    for (i = 0; i < args->N; ++i)
        if (args->valid[i] != 0) {
            ++c->calls;
            if (LANE_U(args->hit, args->N, 5, i) == c->prim && LANE_U(args->hit, args->N, 6, i) == 0)
                args->valid[i] = 0;
        }
}

static int mode_packets(const scene_in *s, int W, int H, int K)
{
    emb e;
    int n = W * H, widths[3] = {4, 8, 16}, native[3], wi, bad = 0, checked = 0, k;
    float(*rays)[6] = malloc(sizeof(float[6]) * (size_t)n);
    struct RTCRayHit *one = malloc(sizeof *one * (size_t)n);
    int *occ1 = malloc(sizeof(int) * (size_t)n);
    ig_embree_hit *rec1 = malloc(sizeof *rec1 * (size_t)n), *recn = malloc(sizeof *recn * (size_t)n);
    if (!rays || !one || !occ1 || !rec1 || !recn)
        fail("out of memory");
    /* with K: a context filter that rejects object K, in every call below */
    embree_scene(s, &e, 0, K >= 0 ? RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION : RTC_SCENE_FLAG_NONE);
    /* Embree 3 keeps a lane that the valid mask switches off untouched only at widths its ISA runs natively; a
     * wider packet is traced as a stream of single rays, where the valid mask is not read and a lane is off only
     * when tnear > tfar (rtcIntersect1M's rule). So lanes off at an emulated width are marked both ways, as a
     * caller must for every ISA, and at a native width by the valid mask alone. */
    for (wi = 0; wi < 3; ++wi)
        native[wi] =
            rtcGetDeviceProperty(e.dev, (enum RTCDeviceProperty)(RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED + wi)) != 0;
    reject_context ctx1; /* double records of every ray, by its id (= its index) */
    ig_embree_context_init(&ctx1.ig, rec1, (unsigned)n);
    ctx1.prim = (unsigned)K;
    ctx1.calls = 0;
    ctx1.ig.rtc.filter = K >= 0 ? reject_prim : NULL;
    for (k = 0; k < n; ++k) {
        reject_context ctx = ctx1;
        struct RTCRay r;
        camera_ray(s, W, H, k % W, k / W, rays[k], rays[k] + 3);
        set_ray(&one[k].ray, rays[k], rays[k] + 3, 0.0f, INFINITY, ~0u, (unsigned)k);
        one[k].hit.geomID = one[k].hit.primID = one[k].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(e.scene, &ctx1.ig.rtc, &one[k]);
        /* a shadow-like ray: from 40 % of the way to the hit (or far out) toward the light */
        set_ray(&r, rays[k], rays[k] + 3, 0.0f, isfinite(one[k].ray.tfar) ? 0.999f * one[k].ray.tfar : 20.0f, ~0u,
                (unsigned)k);
        ig_embree_context_init(&ctx.ig, NULL, 0);
        ctx.ig.rtc.filter = ctx1.ig.rtc.filter;
        rtcOccluded1(e.scene, &ctx.ig.rtc, &r);
        occ1[k] = r.tfar < 0.0f;
    }
    for (wi = 0; wi < 3; ++wi) {
        int N = widths[wi];
        reject_context ctx = ctx1;
        ig_embree_context_init(&ctx.ig, recn, (unsigned)n); /* (which clears the filter) */
        ctx.ig.rtc.filter = ctx1.ig.rtc.filter;
        for (k = 0; k + N <= n; k += N) {
            union { /* Embree's aligned packet types; LANE_F indexes them as RTCRayHitN / RTCRayN */
                struct RTCRayHit4 r4;
                struct RTCRayHit8 r8;
                struct RTCRayHit16 r16;
            } rh;
            union {
                struct RTCRay4 r4;
                struct RTCRay8 r8;
                struct RTCRay16 r16;
            } orr;
            union {
                struct RTCRay16 align; /* 64-byte alignment */
                int v[16];
            } va;
            float *buf = (float *)&rh, *obuf = (float *)&orr;
            int *valid = va.v, i, f;
            for (i = 0; i < N; ++i) {
                int j = k + i;
                valid[i] = (j % 7 == 3) ? 0 : -1; /* some lanes off: they must come back untouched */
                for (f = 0; f < 3; ++f) {
                    LANE_F(buf, N, f, i) = LANE_F(obuf, N, f, i) = rays[j][f];
                    LANE_F(buf, N, 4 + f, i) = LANE_F(obuf, N, 4 + f, i) = rays[j][3 + f];
                }
                LANE_F(buf, N, 3, i) = LANE_F(obuf, N, 3, i) = 0.0f;
                LANE_F(buf, N, 7, i) = LANE_F(obuf, N, 7, i) = 0.0f;
                LANE_F(buf, N, 8, i) = INFINITY;
                LANE_F(obuf, N, 8, i) = isfinite(one[j].ray.tfar) ? 0.999f * one[j].ray.tfar : 20.0f;
                if (!valid[i] && !native[wi]) { /* emulated width: off by the stream rule too */
                    LANE_F(buf, N, 3, i) = LANE_F(obuf, N, 3, i) = 1.0f;
                    LANE_F(buf, N, 8, i) = LANE_F(obuf, N, 8, i) = 0.0f;
                }
                LANE_U(buf, N, 9, i) = LANE_U(obuf, N, 9, i) = ~0u;
                LANE_U(buf, N, 10, i) = LANE_U(obuf, N, 10, i) = (unsigned)j;
                LANE_U(buf, N, 11, i) = LANE_U(obuf, N, 11, i) = 0;
                LANE_U(buf, N, 12 + 6, i) = LANE_U(buf, N, 12 + 5, i) = LANE_U(buf, N, 12 + 7, i) =
                    RTC_INVALID_GEOMETRY_ID;
            }
            if (N == 4) {
                rtcIntersect4(valid, e.scene, &ctx.ig.rtc, &rh.r4);
                rtcOccluded4(valid, e.scene, &ctx.ig.rtc, &orr.r4);
            } else if (N == 8) {
                rtcIntersect8(valid, e.scene, &ctx.ig.rtc, &rh.r8);
                rtcOccluded8(valid, e.scene, &ctx.ig.rtc, &orr.r8);
            } else {
                rtcIntersect16(valid, e.scene, &ctx.ig.rtc, &rh.r16);
                rtcOccluded16(valid, e.scene, &ctx.ig.rtc, &orr.r16);
            }
            for (i = 0; i < N; ++i) {
                int j = k + i, same;
                const struct RTCHit *h1 = &one[j].hit;
                ++checked;
                if (!valid[i]) {
                    float far0 = native[wi] ? INFINITY : 0.0f, ofar0 = native[wi] ? 0.999f * one[j].ray.tfar : 0.0f;
                    if (native[wi] && !isfinite(one[j].ray.tfar))
                        ofar0 = 20.0f;
                    same = LANE_F(buf, N, 8, i) == far0 && LANE_U(buf, N, 12 + 6, i) == RTC_INVALID_GEOMETRY_ID &&
                           LANE_F(obuf, N, 8, i) == ofar0;
                } else {
                    same = memcmp(&LANE_F(buf, N, 8, i), &one[j].ray.tfar, sizeof(float)) == 0 &&
                           LANE_U(buf, N, 12 + 6, i) == h1->geomID && (LANE_F(obuf, N, 8, i) < 0.0f) == occ1[j];
                    if (h1->geomID != RTC_INVALID_GEOMETRY_ID) /* the rest of a hit (a miss leaves it unset) */
                        same = same && LANE_U(buf, N, 12 + 5, i) == h1->primID &&
                               LANE_U(buf, N, 12 + 7, i) == h1->instID[0] && LANE_F(buf, N, 12, i) == h1->Ng_x &&
                               LANE_F(buf, N, 13, i) == h1->Ng_y && LANE_F(buf, N, 14, i) == h1->Ng_z;
                    /* the double distance too, to rounding: the solve's shift point depends on tfar, which
                     * depends on the order the primitives are visited in (the tracer's own BVH does the same) */
                    if (h1->geomID == e.alg_geom)
                        same = same && fabs(rec1[j].t - recn[j].t) <= 1e-13 * rec1[j].t;
                }
                if (!same && bad++ < 5)
                    fprintf(stderr,
                            "packets: width %d ray %d (valid %d) differs from rtcIntersect1: tfar %g/%g geom %u/%u "
                            "occluded %d/%d prim %u/%u t %.17g/%.17g Ng %g/%g\n",
                            N, j, valid[i], LANE_F(buf, N, 8, i), one[j].ray.tfar, LANE_U(buf, N, 18, i), h1->geomID,
                            LANE_F(obuf, N, 8, i) < 0.0f, occ1[j], LANE_U(buf, N, 17, i), h1->primID, recn[j].t,
                            rec1[j].t, LANE_F(buf, N, 12, i), h1->Ng_x);
            }
        }
    }
    printf("packets: %d lanes of width 4, 8, 16 checked, %d differ; filter rejecting object %d: %d calls; native "
           "widths%s%s%s\n",
           checked, bad, K, ctx1.calls, native[0] ? " 4" : "", native[1] ? " 8" : "", native[2] ? " 16" : "");
    free(rays);
    free(one);
    free(occ1);
    free(rec1);
    free(recn);
    embree_free(s, &e);
    return bad != 0;
}

static int mode_surface(const scene_in *s, int W, int H)
{
    rt_scene *t = tracer_scene(s, -1, 1, 1);
    emb e;
    int n = W * H, k, rays = 0, idbad = 0, tbad = 0, early = 0;
    const float tnear = 1e-4f;
    embree_scene(s, &e, 0, RTC_SCENE_FLAG_NONE);
    for (k = 0; k < n; ++k) {
        float o[3], d[3], so[3], sd[3];
        double dd[3], r[3], len;
        rt_hit h, h2;
        answer a, b;
        int i, pass;
        camera_ray(s, W, H, k % W, k / W, o, d);
        if (tracer_closest(s, t, -1, 1, o, d, 0.0, &h).obj < 0)
            continue;
        for (i = 0; i < 3; ++i)
            dd[i] = d[i];
        rt_reflect(dd, h.n, r);
        for (pass = 0; pass < 2; ++pass) { /* the mirror ray, then the same ray back into the surface */
            len = pass ? -1.0 : 1.0;
            for (i = 0; i < 3; ++i) {
                so[i] = (float)h.p[i]; /* on the surface, to float rounding: no offset */
                sd[i] = (float)(len * r[i]);
            }
            a = tracer_closest(s, t, -1, 1, so, sd, tnear, &h2);
            b = embree_closest(s, &e, so, sd, tnear, ~0u, NULL);
            ++rays;
            if (b.obj >= 0 && b.t < tnear)
                ++early;
            if (a.obj != b.obj)
                ++idbad;
            else if (a.obj >= 0 && a.obj < s->n && fabs(a.t - b.t) > 1e-9 * fabs(a.t))
                ++tbad;
        }
    }
    printf("surface: %d rays from hit points, %d hits before tnear, %d objects differ, %d distances differ\n", rays,
           early, idbad, tbad);
    embree_free(s, &e);
    rt_scene_free(t);
    return early != 0 || idbad * 10000 > rays || tbad != 0;
}

static int mode_masks(const scene_in *s, int W, int H)
{
    rt_scene *all = tracer_scene(s, -1, 1, 1), *objs = tracer_scene(s, -1, 1, 0), *gr = tracer_scene(s, -1, 0, 1);
    emb e;
    int n = W * H, k, bad[4] = {0, 0, 0, 0}, hits[4] = {0, 0, 0, 0}, total = 0;
    unsigned masks[4] = {1, 2, 3, 4};
    embree_scene(s, &e, 0, RTC_SCENE_FLAG_NONE);
    for (k = 0; k < n; ++k) {
        float o[3], d[3];
        rt_hit h;
        int mi;
        camera_ray(s, W, H, k % W, k / W, o, d);
        for (mi = 0; mi < 4; ++mi) {
            const rt_scene *t = masks[mi] == 1 ? gr : masks[mi] == 2 ? objs : all;
            answer a = tracer_closest(s, t, -1, masks[mi] != 1, o, d, 0.0, &h);
            answer b = embree_closest(s, &e, o, d, 0.0f, masks[mi], NULL);
            if (masks[mi] == 4)
                a.obj = -1; /* no geometry has mask 4 */
            hits[mi] += b.obj >= 0;
            bad[mi] += a.obj != b.obj;
        }
        ++total;
    }
    printf("masks: %d rays; mask 1 (ground) %d hits %d differ; mask 2 (shapes) %d hits %d differ; mask 3 %d hits %d "
           "differ; mask 4 %d hits\n",
           total, hits[0], bad[0], hits[1], bad[1], hits[2], bad[2], hits[3]);
    embree_free(s, &e);
    rt_scene_free(all);
    rt_scene_free(objs);
    rt_scene_free(gr);
    return (bad[0] + bad[1] + bad[2]) * 10000 > 3 * total || hits[3] != 0 || hits[1] == 0 || hits[0] == 0;
}

static int mode_filter(const scene_in *s, int W, int H, int K)
{
    rt_scene *t = tracer_scene(s, K, 1, 1), *tall = tracer_scene(s, -1, 1, 1);
    emb e;
    int n = W * H, k, variant, bad[2] = {0, 0}, obad[2] = {0, 0}, tbad = 0, changed = 0, shadows = 0, calls = 0;
    embree_scene(s, &e, 0, RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION); /* Embree runs context filters only then */
    if (e.alg_geom != 0)
        fail("the shapes' geometry must be geometry 0");
    for (variant = 0; variant < 2; ++variant) {
        RTCGeometry g = rtcGetGeometry(e.scene, e.alg_geom);
        /* variant 0: the context's filter; variant 1: the geometry's intersection and occlusion filters */
        rtcSetGeometryIntersectFilterFunction(g, variant ? reject_prim : NULL);
        rtcSetGeometryOccludedFilterFunction(g, variant ? reject_prim : NULL);
        rtcCommitGeometry(g);
        rtcCommitScene(e.scene);
        for (k = 0; k < n; ++k) {
            float o[3], d[3], so[3], sd[3];
            rt_hit h, hall;
            reject_context rc;
            struct RTCRayHit rh;
            answer a, b;
            double dt;
            camera_ray(s, W, H, k % W, k / W, o, d);
            a = tracer_closest(s, t, K, 1, o, d, 0.0, &h);
            changed += variant == 0 && tracer_closest(s, tall, -1, 1, o, d, 0.0, &hall).obj == K;
            ig_embree_hit rec;
            ig_embree_context_init(&rc.ig, &rec, 1);
            rc.prim = (unsigned)K;
            rc.calls = 0;
            rc.ig.rtc.filter = variant ? NULL : reject_prim;
            set_ray(&rh.ray, o, d, 0.0f, INFINITY, ~0u, 0);
            rh.hit.geomID = rh.hit.primID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(e.scene, &rc.ig.rtc, &rh);
            calls += rc.calls;
            b.obj = embree_object(s, &e, rh.hit.geomID, rh.hit.primID, rh.hit.instID[0]);
            b.t = ig_embree_double_t(&rc.ig, 0, rh.hit.geomID, rh.hit.primID, rh.hit.instID[0], &dt) ? dt : rh.ray.tfar;
            bad[variant] += a.obj != b.obj;
            tbad += a.obj == b.obj && a.obj >= 0 && a.obj < s->n && fabs(a.t - b.t) > 1e-9 * a.t;
            if (a.obj >= 0) {
                struct RTCRay r;
                shadow_ray(s, &h, so, sd);
                rc.calls = 0;
                set_ray(&r, so, sd, 0.0f, 1.0f, ~0u, 0);
                rtcOccluded1(e.scene, &rc.ig.rtc, &r);
                obad[variant] += (r.tfar < 0.0f) != tracer_occluded(t, so, sd);
                shadows++;
            }
        }
    }
    printf("filter: object %d rejected on %d pixels; context filter %d differ, geometry filter %d differ, %d "
           "distances differ; shadow rays %d, occlusion differs on %d and %d; %d filter calls\n",
           K, changed, bad[0], bad[1], tbad, shadows, obad[0], obad[1], calls);
    embree_free(s, &e);
    rt_scene_free(t);
    rt_scene_free(tall);
    return changed == 0 || calls == 0 || (bad[0] + bad[1]) * 10000 > 2 * n || tbad != 0 || obad[0] + obad[1] != 0;
}

/* Several threads tracing the same rays at once, each with its own double-hit table, against one thread. */
typedef struct thread_job {
    const scene_in *s;
    const emb *e;
    int W, H;
    float *tfar;
    unsigned *ids;
    ig_embree_hit *rec;
} thread_job;

static void *trace_all(void *arg)
{
    thread_job *j = (thread_job *)arg;
    int n = j->W * j->H, k;
    ig_embree_context ctx;
    ig_embree_context_init(&ctx, j->rec, (unsigned)n);
    for (k = 0; k < n; ++k) {
        float o[3], d[3];
        struct RTCRayHit rh;
        camera_ray(j->s, j->W, j->H, k % j->W, k / j->W, o, d);
        set_ray(&rh.ray, o, d, 0.0f, INFINITY, ~0u, (unsigned)k);
        rh.hit.geomID = rh.hit.primID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(j->e->scene, &ctx.rtc, &rh);
        j->tfar[k] = rh.ray.tfar;
        j->ids[2 * k] = rh.hit.geomID;
        j->ids[2 * k + 1] = rh.hit.primID;
    }
    return NULL;
}

static int mode_threads(const scene_in *s, int W, int H, int nthreads)
{
    emb e;
    int n = W * H, t, k, bad = 0;
    thread_job jobs[9];
    pthread_t th[8];
    if (nthreads < 1 || nthreads > 8)
        fail("1 to 8 threads");
    embree_scene(s, &e, 0, RTC_SCENE_FLAG_NONE);
    for (t = 0; t <= nthreads; ++t) { /* job 0: alone, first; jobs 1..nthreads: at once */
        jobs[t].s = s, jobs[t].e = &e, jobs[t].W = W, jobs[t].H = H;
        jobs[t].tfar = malloc(sizeof(float) * (size_t)n);
        jobs[t].ids = malloc(sizeof(unsigned) * 2 * (size_t)n);
        jobs[t].rec = malloc(sizeof(ig_embree_hit) * (size_t)n);
        if (!jobs[t].tfar || !jobs[t].ids || !jobs[t].rec)
            fail("out of memory");
    }
    trace_all(&jobs[0]);
    for (t = 1; t <= nthreads; ++t)
        if (pthread_create(&th[t - 1], NULL, trace_all, &jobs[t]) != 0)
            fail("cannot start a thread");
    for (t = 1; t <= nthreads; ++t)
        pthread_join(th[t - 1], NULL);
    for (t = 1; t <= nthreads; ++t)
        for (k = 0; k < n; ++k)
            bad += memcmp(&jobs[t].tfar[k], &jobs[0].tfar[k], sizeof(float)) != 0 ||
                   jobs[t].ids[2 * k] != jobs[0].ids[2 * k] || jobs[t].ids[2 * k + 1] != jobs[0].ids[2 * k + 1] ||
                   (jobs[0].ids[2 * k] == e.alg_geom && jobs[t].rec[k].t != jobs[0].rec[k].t);
    printf("threads: %d threads x %d rays against one thread, %d differ\n", nthreads, n, bad);
    for (t = 0; t <= nthreads; ++t) {
        free(jobs[t].tfar);
        free(jobs[t].ids);
        free(jobs[t].rec);
    }
    embree_free(s, &e);
    return bad != 0;
}

/* The calling thread's CPU time: both tracers run in this thread (Embree's rtcIntersect too), and a shared
 * machine's other work does not count against either. */
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int mode_bench(const scene_in *s, int W, int H, int reps)
{
    rt_scene *t = s->n > 0 || s->ground > 0 ? tracer_scene(s, -1, 1, 1) : NULL;
    emb e;
    int n = W * H, k, rep;
    float(*rays)[6] = malloc(sizeof(float[6]) * (size_t)n), (*sh)[6] = malloc(sizeof(float[6]) * (size_t)n);
    double sink = 0.0;
    if (!rays || !sh)
        fail("out of memory");
    embree_scene(s, &e, 0, RTC_SCENE_FLAG_NONE);
    for (k = 0; k < n; ++k) {
        ig_embree_context ctx;
        struct RTCRayHit rh;
        int i;
        camera_ray(s, W, H, k % W, k / W, rays[k], rays[k] + 3);
        ig_embree_context_init(&ctx, NULL, 0);
        set_ray(&rh.ray, rays[k], rays[k] + 3, 0.0f, INFINITY, ~0u, 0);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(e.scene, &ctx.rtc, &rh);
        for (i = 0; i < 3; ++i) { /* shadow rays from just before the Embree hit (or the far end) to the light */
            float tt = isfinite(rh.ray.tfar) ? 0.999f * rh.ray.tfar : 30.0f;
            sh[k][i] = rays[k][i] + tt * rays[k][3 + i];
            sh[k][3 + i] = (float)(s->light[i] - sh[k][i]);
        }
    }
    for (rep = 0; rep < reps; ++rep) { /* interleaved: every method once per repetition */
        double t0, ours = 0, emb1 = 0, emb8 = 0, ours_sh = 0, emb_sh = 0;
        int hits = 0;
        if (t) {
            t0 = now();
            for (k = 0; k < n; ++k) {
                rt_hit h;
                double o[3] = {rays[k][0], rays[k][1], rays[k][2]}, d[3] = {rays[k][3], rays[k][4], rays[k][5]};
                hits += rt_scene_intersect(t, o, d, 0.0, INFINITY, &h);
            }
            ours = n / (now() - t0);
            t0 = now();
            for (k = 0; k < n; ++k)
                hits += tracer_occluded(t, sh[k], sh[k] + 3);
            ours_sh = n / (now() - t0);
        }
        t0 = now();
        for (k = 0; k < n; ++k) {
            ig_embree_context ctx;
            struct RTCRayHit rh;
            ig_embree_context_init(&ctx, NULL, 0);
            set_ray(&rh.ray, rays[k], rays[k] + 3, 0.0f, INFINITY, ~0u, 0);
            rh.hit.geomID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(e.scene, &ctx.rtc, &rh);
            sink += rh.ray.tfar;
        }
        emb1 = n / (now() - t0);
        t0 = now();
        for (k = 0; k + 8 <= n; k += 8) {
            struct RTCRayHit8 rh;
            ig_embree_context ctx;
            union {
                struct RTCRay8 align; /* rtcIntersect8 loads the valid mask aligned */
                int v[8];
            } va;
            int *valid = va.v, i;
            for (i = 0; i < 8; ++i) {
                valid[i] = -1;
                rh.ray.org_x[i] = rays[k + i][0], rh.ray.org_y[i] = rays[k + i][1], rh.ray.org_z[i] = rays[k + i][2];
                rh.ray.dir_x[i] = rays[k + i][3], rh.ray.dir_y[i] = rays[k + i][4], rh.ray.dir_z[i] = rays[k + i][5];
                rh.ray.tnear[i] = 0.0f, rh.ray.tfar[i] = INFINITY, rh.ray.time[i] = 0.0f;
                rh.ray.mask[i] = ~0u, rh.ray.id[i] = 0, rh.ray.flags[i] = 0;
                rh.hit.geomID[i] = rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
            }
            ig_embree_context_init(&ctx, NULL, 0);
            ctx.rtc.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            rtcIntersect8(valid, e.scene, &ctx.rtc, &rh);
            sink += rh.ray.tfar[0];
        }
        emb8 = (n - n % 8) / (now() - t0);
        t0 = now();
        for (k = 0; k < n; ++k) {
            ig_embree_context ctx;
            struct RTCRay r;
            ig_embree_context_init(&ctx, NULL, 0);
            set_ray(&r, sh[k], sh[k] + 3, 0.0f, 1.0f, ~0u, 0);
            rtcOccluded1(e.scene, &ctx.rtc, &r);
            sink += r.tfar;
        }
        emb_sh = n / (now() - t0);
        printf("bench: rays %d tracer %.6g embree1 %.6g embree8 %.6g tracer_shadow %.6g embree_shadow %.6g hits %d\n",
               n, ours, emb1, emb8, ours_sh, emb_sh, hits);
    }
    if (sink == 12345.678)
        printf("(sink)\n");
    free(rays);
    free(sh);
    embree_free(s, &e);
    if (t)
        rt_scene_free(t);
    return 0;
}

int main(int argc, char **argv)
{
    scene_in s;
    int W, H, rc = 2;
    if (argc < 5)
        fail("usage: embree_check MODE SCENE W H [ARG]");
    read_scene(argv[2], &s);
    W = atoi(argv[3]);
    H = atoi(argv[4]);
    if (W <= 0 || H <= 0)
        fail("bad size");
    if (!strcmp(argv[1], "agree") && argc > 6)
        rc = mode_agree(&s, W, H, argv[5], atoi(argv[6]));
    else if (!strcmp(argv[1], "packets"))
        rc = mode_packets(&s, W, H, argc > 5 ? atoi(argv[5]) : -1);
    else if (!strcmp(argv[1], "surface"))
        rc = mode_surface(&s, W, H);
    else if (!strcmp(argv[1], "masks"))
        rc = mode_masks(&s, W, H);
    else if (!strcmp(argv[1], "filter") && argc > 5)
        rc = mode_filter(&s, W, H, atoi(argv[5]));
    else if (!strcmp(argv[1], "threads") && argc > 5)
        rc = mode_threads(&s, W, H, atoi(argv[5]));
    else if (!strcmp(argv[1], "bench") && argc > 5)
        rc = mode_bench(&s, W, H, atoi(argv[5]));
    else
        fail("unknown mode");
    free(s.shape);
    free(s.params);
    free(s.m);
    return rc;
}
