/* Certified primary rays: for a ray, a proof in double precision that its first hit (which object, or none)
 * is what the exact ray meets first, or the reason why there is none. docs/certify.md states what a
 * certificate is and what it rests on; implgen render --certify writes the per-pixel map.
 *
 * Nothing here runs during a plain render: the certify pass (rt_render_certify) is a separate pass over the
 * same primary rays as rt_render_run's, asked for explicitly.
 */
#ifndef IMPLGEN_CERTIFY_H
#define IMPLGEN_CERTIFY_H

#include "tracer.h"

/* The codes of the map: 0 certified miss, 1 certified hit, 2 and up not certified, one code per reason. */
enum {
    RT_CERT_MISS = 0,     /* certified: the exact ray meets no object */
    RT_CERT_HIT = 1,      /* certified: the object the tracer shows is the one the exact ray meets first */
    RT_CERT_TANGENT = 2,  /* a tangent or multiple root: no interval holds exactly one simple root */
    RT_CERT_SINGULAR = 3, /* the same at a point where grad f vanishes (a node, a cusp) */
    RT_CERT_NOISE = 4,    /* a simple root within the rounding noise of the range's ends (box face, ray start) */
    RT_CERT_TIE = 5,      /* two objects' (or CSG operands') first hits not told apart */
    RT_CERT_OVERFLOW = 6, /* a coefficient or its bound not finite */
    RT_CERT_BUDGET = 7,   /* the subdivision ran out of its budget */
    RT_CERT_NOBOUND = 8,  /* the shape offers no error-bounded coefficients (a hand-made shape), or a clip region */
    RT_CERT_FAR = 9,      /* an unbounded object: a root beyond the tracer's far distance not ruled out */
    RT_CERT_WRONG = 10,   /* the certified first hit is not what the tracer shows */
    RT_CERT_NCODES = 11
};

/* The name of a code ("miss", "hit", "tangent", ...), or NULL. */
const char *rt_certify_reason(int code);

/* One ray o + t d, t > 0: the code, and in *object the object the code is about (the certified or shown hit, or
 * the object whose certificate failed), -1 for none. The tracer's own answer (rt_scene_closest) is compared. */
int rt_certify_ray(const rt_scene *s, const double o[3], const double d[3], int *object);

/* The certify pass of a render: for each pixel of the rows rt_render_run renders, the code of its primary rays
 * (every sample's ray certified, the same answer for all, or the pixel is not: the first failing sample's
 * code) into map, and its object into objects (may be NULL), row y0 first. Returns 0, or -1 when threads could
 * not be started. */
int rt_render_certify(rt_render *r, unsigned char *map, int *objects);

/* tracer_render.c: the primary rays of pixel (x, y), as rt_render_run traces them: eye into o, spp directions
 * into dirs (3 each). Returns spp. */
int rt_render_primary_rays(const rt_render *r, int x, int y, double o[3], double *dirs);
/* The scene of a render context. */
const rt_scene *rt_render_scene(const rt_render *r);
/* The rows [*y0, *y1), width, spp and thread count of a render context. */
void rt_render_shape(const rt_render *r, int *y0, int *y1, int *width, int *spp, int *threads);

/* ---- certify_poly.c: the polynomial certificate (exposed for tests) ---- */
/* The first root of the polynomial with coefficient balls (c[k], e[k]), degree n, on [a, b]: 1 and an interval
 * [*lo, *hi] holding exactly one root, a simple one, and no other root in [a, *hi] -- narrowed until at most
 * rel x |origin + *lo| wide where its halves tell; 0 when [a, b] holds no root; or -code (RT_CERT_TANGENT,
 * RT_CERT_NOISE, RT_CERT_BUDGET, RT_CERT_OVERFLOW) with *lo = *hi the start of the first undecided piece. */
int rt_certify_first_root(const double *c, const double *e, int n, double a, double b, double origin, double rel,
                          double *lo, double *hi);
/* All roots on [a, b]: up to n intervals (lo, hi: room for n + 1), each holding exactly one simple root, none
 * elsewhere on [a, b], and the certified sign of p at a in *sign_a. Returns their count, or -code as above. */
int rt_certify_roots(const double *c, const double *e, int n, double a, double b, double origin, double rel, double *lo,
                     double *hi, int *sign_a);

#endif
