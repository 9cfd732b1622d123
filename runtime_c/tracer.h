/* The scene tracer: algebraic shapes under affine transforms, CSG, Whitted-style shading with glass.
 *
 * Who calls this: implgen.scene.renderjob through ctypes (signatures in implgen.scene.tracer; one shared library
 * per scene, built by implgen.compile.library from this runtime plus the generated shapes the scene uses), and the
 * C test drivers in tests/c/tracer_*.c. Nothing here has global mutable state: a scene is an `rt_scene` value
 * built once and then read by any number of render threads; a render's state (progress, ray counts, cancel
 * flag) lives in an `rt_render` context.
 *
 * Conventions (see docs/tracer.md for the user-level description):
 *  - Transforms are affine 3x4 matrices, row-major: m[0..3] = (a00 a01 a02 tx), m[4..7], m[8..11].
 *    An object maps object space to world space by M; rays go to object space by M^-1 and, because the map
 *    is affine, the ray parameter t is the same in both spaces (directions are not renormalised).
 *  - Inside a shape is f < 0. A top-level leaf is an algebraic SURFACE (every root of f along the ray is a
 *    hit; the spec's bounds clip it). Inside a CSG node a leaf is the SOLID {f < 0} cut by its bounds box
 *    (the box faces close it), and nodes combine solids.
 *  - Secondary rays start at rt_spawn_origin(): the hit point moved off the surface, along the normal, by a
 *    bound on the hit point's error (rt_hit.err) -- never by a fixed epsilon.
 */
#ifndef IMPLGEN_TRACER_H
#define IMPLGEN_TRACER_H

#include "shape.h"

#define RT_VERSION 1

/* Node kinds. */
enum { RT_LEAF = 0, RT_UNION = 1, RT_INTERSECTION = 2, RT_DIFFERENCE = 3 };

/* Clip kinds of a top-level leaf (rt_scene_set_clip): the surface is shown only inside a ball or a cube. */
enum { RT_CLIP_NONE = 0, RT_CLIP_SPHERE = 1, RT_CLIP_BOX = 2 };

/* Limits. implgen.scene.load checks scenes against RT_MAX_CSG_DEPTH, RT_MAX_DEPTH and RT_MAX_SPP too, reading
 * the numbers from this header (implgen.abi). */
#define RT_MAX_CSG_DEPTH 96 /* depth of the binary CSG tree below a top-level object */
#define RT_MAX_SPANS 64     /* inside-intervals kept per CSG node and ray (the nearest ones) */
#define RT_MAX_MEDIA 8      /* nested transparent media a ray can be inside at once */
#define RT_MAX_DEPTH 64     /* hard cap on the recursion depth a render may ask for */
#define RT_MAX_SPP 4096     /* samples per pixel a render may ask for */

/* Material, passed as RT_MATERIAL_DOUBLES packed doubles in this order. */
typedef struct rt_material {
    double color[3];      /* base colour (linear, 0..1) */
    double color2[3];     /* second checker colour */
    double checker_scale; /* > 0: 3-D checker of colour/color2 with this cell size in object units; 0: solid */
    double ambient, diffuse, specular, shininess;
    double reflectivity;  /* mirror weight, 0..1 */
    double transparency;  /* 0: opaque .. 1: clear; the rest is the local (Phong) term */
    double ior;           /* index of refraction of the inside */
    double absorption[3]; /* Beer-Lambert coefficients per world unit, per channel (inside the solid) */
    double two_sided;     /* 1: the back of the surface (its f < 0 side, where the normal points away from the
                             viewer) shows inside instead of the base colour; 0: both sides the same */
    double inside[3];     /* the back's colour when two_sided (linear, 0..1) */
} rt_material;
#define RT_MATERIAL_DOUBLES 21

/* One ray/scene hit, everything in world space. */
typedef struct rt_hit {
    double t;     /* ray parameter: p = o + t d */
    double p[3];  /* hit point */
    double n[3];  /* unit normal, pointing out of the solid that was hit (for a CSG difference, out of
                        the result: the subtracted part's normal is flipped); for a top-level surface,
                        grad f / |grad f| */
    double err;   /* bound on the hit point's distance from the true surface, world units */
    double po[3]; /* hit point in the leaf's object space (for textures) */
    double no[3]; /* the leaf's object-space unit normal, oriented like n */
    int object;   /* index of the top-level object (order of rt_scene_add_object) */
    int leaf;     /* node index of the leaf whose surface was hit */
    int face;     /* 0: the leaf's surface f = 0; +-(1..3): a face of the leaf's bounds box (CSG only) */
    int material; /* material index */
    int entering; /* 1: the ray goes into the solid at p, 0: it comes out */
    int singular; /* 1: grad f vanished at p; n is a fallback facing the ray */
} rt_hit;

typedef struct rt_scene rt_scene;
typedef struct rt_render rt_render;

/* ---- building a scene (tracer_scene.c) ---- */
rt_scene *rt_scene_new(void);
void rt_scene_free(rt_scene *s);
/* Each returns the new item's index, or -1 on bad input (message in rt_scene_error). */
int rt_scene_add_material(rt_scene *s, const double *packed /* RT_MATERIAL_DOUBLES */);
int rt_scene_add_leaf(rt_scene *s, const ig_shape *shape, const double *params, int nparams,
                      const double *object_to_world /* 12 */, int material);
int rt_scene_add_csg(rt_scene *s, int op, int left, int right, int material);
int rt_scene_add_object(rt_scene *s, int node); /* a top-level object: a leaf or a CSG root */
/* Show only the part of a leaf's surface inside the ball of radius `size` about `center` (RT_CLIP_SPHERE) or the
 * cube of half-edge `size` (RT_CLIP_BOX), both in the leaf's object space; RT_CLIP_NONE: all of it. No cap: the
 * surface is cut open, and its back shows through (a two-sided material colours it). For a leaf that is a
 * top-level object; a clipped leaf cannot be a CSG operand (use a CSG intersection to cut a solid). Returns 0,
 * or -1 with a message (not a leaf, used in CSG, size not finite and > 0, scene committed). */
int rt_scene_set_clip(rt_scene *s, int node, int kind, const double center[3], double size);
int rt_scene_add_light(rt_scene *s, const double position[3], const double color[3] /* colour x intensity */);
void rt_scene_set_camera(rt_scene *s, const double eye[3], const double look_at[3], const double up[3],
                         double vfov_degrees);
void rt_scene_set_background(rt_scene *s, const double color[3]);
/* Computes boxes and the BVH. Returns 0, or -1 with a message. No changes after a successful commit. */
int rt_scene_commit(rt_scene *s);
const char *rt_scene_error(const rt_scene *s);
/* The distance that stands in for infinity on unbounded shapes: 1e5 x the scene's size. */
double rt_scene_far(const rt_scene *s);

/* ---- ray queries (tracer_hit.c, tracer_csg.c) ---- */
/* Closest hit with tmin < t < tmax (tmax may be INFINITY). Returns 1 and fills *hit, or 0. */
int rt_scene_intersect(const rt_scene *s, const double o[3], const double d[3], double tmin, double tmax, rt_hit *hit);
/* The inside-intervals of a node (leaf solid or CSG) along the ray, clipped to [tmin, tmax]: writes
 * pairs t_in[i] < t_out[i] ascending, with the leaf node of each endpoint (-1 where the interval is open
 * because the ray starts or ends inside). Returns the interval count (<= max). For tests and debugging. */
int rt_node_spans(const rt_scene *s, int node, const double o[3], const double d[3], double tmin, double tmax,
                  double *t_in, double *t_out, int *leaf_in, int *leaf_out, int max);

/* ---- optics (tracer_shade.c); directions need not be unit, results are unit ---- */
void rt_reflect(const double d[3], const double n[3], double r[3]);
/* Refraction of d at a surface with unit normal n facing the incoming ray (dot(d, n) < 0), eta = n1 / n2.
 * Returns 0 on total internal reflection, else 1 with the unit refracted direction in t. */
int rt_refract(const double d[3], const double n[3], double eta, double t[3]);
/* Exact unpolarised Fresnel reflectance for cos_i = cos(angle of incidence) >= 0, eta = n1 / n2
 * (1 for total internal reflection). */
double rt_fresnel(double cos_i, double eta);
/* Origin for a secondary ray leaving hit in direction d: hit->p moved by a multiple of hit->err along the
 * normal, to the side d goes to. Trace the new ray from t = 0. */
void rt_spawn_origin(const rt_hit *hit, const double d[3], double origin[3]);

/* ---- rendering (tracer_render.c) ---- */
/* Ray counts by kind, in rt_render_stats order, and the number of samples whose colour came out NaN or
 * infinite (written as 0 so one bad sample cannot spoil an image, but counted so tests can insist on 0). */
enum { RT_RAYS_PRIMARY = 0, RT_RAYS_SHADOW = 1, RT_RAYS_SECONDARY = 2, RT_NONFINITE = 3, RT_NSTATS = 4 };
rt_render *rt_render_new(const rt_scene *s, int width, int height, int spp, int max_depth, int threads,
                         unsigned long seed);
void rt_render_free(rt_render *r);
/* Render only the rows [y0, y1) of the image from now on (a tile), each pixel exactly as in the whole image:
 * samples depend only on the pixel's place in the whole image. Returns 0, or -1 for a range outside
 * [0, height) or empty. */
int rt_render_set_rows(rt_render *r, int y0, int y1);
/* Which pixels a pass renders (rt_render_set_pass): all, those whose x and y are both even, or the others. */
enum { RT_PIXELS_ALL = 0, RT_PIXELS_EVEN = 1, RT_PIXELS_ODD = 2 };
/* The next run is a pass: it adds samples [k0, k1) of each pixel of `pixels` (the samples a whole render takes,
 * in its order) to sums (3 doubles a pixel of the rows rendered, row y0 first; read only when k0 > 0) and writes
 * their mean over samples [0, k1) to rgb (the other pixels' rgb is left as it was). Passes [0, a), [a, b), ...,
 * [., spp) over every pixel leave rgb bit for bit the whole render's. Returns 0, or -1 for bad arguments. */
int rt_render_set_pass(rt_render *r, int k0, int k1, int pixels, double *sums);
/* Renders into rgb ((y1 - y0) * width * 3 floats, row y0 first; all rows unless set). Blocks; safe to call
 * from a thread the caller does not block on. Returns 0, 1 when cancelled, -1 when threads could not be
 * started. */
int rt_render_run(rt_render *r, float *rgb);
int rt_render_progress(rt_render *r); /* rows finished so far (thread-safe) */
void rt_render_cancel(rt_render *r);  /* ask a running render to stop after the current rows */
void rt_render_stats(rt_render *r, double out[RT_NSTATS]);
/* Colour seen along one ray (full shading, recursion), for tests. kind counts are added to stats if given. */
void rt_trace_ray(const rt_scene *s, const double o[3], const double d[3], int max_depth, double rgb[3],
                  double stats[RT_NSTATS]);

#endif
