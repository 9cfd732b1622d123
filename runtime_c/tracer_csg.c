/* Ray/object intersection: algebraic leaves and CSG trees.
 *
 * A CSG leaf is the solid {f < 0} cut by its bounds box. Along a ray it is a list of inside-intervals
 * ("spans"): the roots of f(o + t d) split the clipped ray range into pieces, and the sign of f at each
 * piece's midpoint says inside or outside. Deciding by sign rather than by counting roots makes tangent and
 * double roots (a grazing ray) harmless: the pieces on both sides are both outside (or both inside) and
 * merge. Operators combine span lists of their children with one sweep over the sorted endpoints.
 */
#include "tracer_internal.h"
#include "roots_impl.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* Roots (in t) of a leaf along the object-space ray oo + s u, u the unit direction and s = t L. s and leaf: the
 * scene and the leaf's node index, for the floor report's record (s may be NULL: none). */
static inline int leaf_roots_unit(const rt_scene *s, int leaf, const rt_node *n, const double oo[3], const double u[3],
                                  double L, double lo, double hi, double *r)
{
    int k = ig_shape_solve(n->shape, n->params, &n->prep, oo, u, lo * L, hi * L, IG_ROOTS_AUTO, 0, r, NULL), i;
    (void)s;
    (void)leaf;
    if (s)
        RT_TRACE_SOLVE(s, leaf, oo, u, lo * L, hi * L, IG_ALL_ROOTS, k, r);
    for (i = 0; i < k; ++i)
        r[i] /= L;
    return k;
}

/* Roots of a leaf along an object-space ray, in the ray's own parameter. The solve runs on the unit direction
 * (parameter s = t |d|) so the polynomial does not depend on how much the transform scaled the direction:
 * an object scaled by 1e3 would otherwise hand the solver coefficients c_k ~ 1e-3k. */
int rt_leaf_roots(const rt_node *n, const double oo[3], const double od[3], double lo, double hi, double *r)
{
    double u[3], L = ig_unit_vector(od, u); /* oo, od: already in object space */
    if (!(L > 0.0) || !isfinite(L))
        return 0;
    return leaf_roots_unit(NULL, -1, n, oo, u, L, lo, hi, r);
}

/* A leaf's ray as its solve takes it: origin, direction, inverse direction (NULL when it is not the world
 * ray's), unit direction u and its length L in the leaf's object space. */
typedef struct {
    const double *o, *d, *inv, *u;
    double L;
    double own_o[3], own_d[3], own_u[3];
} leaf_ray;

static void leaf_ray_of(const rt_node *n, const rt_ray *ray, leaf_ray *lr)
{
    lr->o = ray->o;
    lr->d = ray->d;
    lr->inv = ray->inv;
    lr->u = NULL; /* set once the leaf's box is entered (leaf_spans) */
    lr->L = ray->len;
    if (!n->identity) { /* an identity leaf takes the world ray as it is, with its inverse and unit direction */
        rt_xform_point(n->minv, ray->o, lr->own_o);
        rt_xform_vector(n->minv, ray->d, lr->own_d);
        lr->o = lr->own_o;
        lr->d = lr->own_d;
        lr->inv = NULL;
    }
}

/* Breakpoints x[0] = a <= roots <= x[nx - 1] = b (returns nx). A root within rounding of a box face means the
 * surface touches its box there (a cylinder tangent to its box's side): that end is the surface, not the face
 * (*f0, *f1 cleared). */
static int leaf_breakpoints(const double *r, int nr, double a, double b, int *f0, int *f1, double *x)
{
    double tol = 1e-9 * (b - a);
    int i, nx = 0;
    for (i = 0; i < nr; ++i) {
        if (*f0 && fabs(r[i] - a) <= tol)
            *f0 = 0;
        if (*f1 && fabs(r[i] - b) <= tol)
            *f1 = 0;
    }
    x[nx++] = a;
    for (i = 0; i < nr; ++i)
        if (r[i] > x[nx - 1] && r[i] < b)
            x[nx++] = r[i];
    x[nx++] = b;
    return nx;
}

/* The inside-intervals of leaf k between the breakpoints x[0..nx): the sign of f at each piece's midpoint (NaN
 * counts as outside); adjacent inside pieces merge. ends: what a span starting at x[0] or ending at x[nx - 1]
 * ends on (a box face of this leaf, or -1: open where the ray's range starts or stops inside). */
static int spans_by_sign(const rt_node *n, int k, const leaf_ray *lr, const double *x, int nx, const rt_end ends[2],
                         rt_span *out, int max)
{
    rt_end start;
    int i, cnt = 0, inside_prev = 0;
    start.t = x[0];
    start.leaf = -1;
    start.face = 0;
    for (i = 0; i + 1 < nx; ++i) {
        double tm = 0.5 * (x[i] + x[i + 1]), q[3];
        int inside;
        q[0] = lr->o[0] + tm * lr->d[0];
        q[1] = lr->o[1] + tm * lr->d[1];
        q[2] = lr->o[2] + tm * lr->d[2];
        inside = n->shape->value(q, n->params) < 0.0;
        if (inside && !inside_prev) {
            start.t = x[i];
            start.leaf = i == 0 ? ends[0].leaf : k;
            start.face = i == 0 ? ends[0].face : 0;
        } else if (!inside && inside_prev && cnt < max) {
            out[cnt].in = start;
            out[cnt].out.t = x[i];
            out[cnt].out.leaf = k;
            out[cnt].out.face = 0;
            ++cnt;
        }
        inside_prev = inside;
    }
    if (inside_prev && cnt < max) {
        out[cnt].in = start;
        out[cnt].out = ends[1];
        ++cnt;
    }
    return cnt;
}

/* Spans of one leaf solid over [a, b]. */
static int leaf_spans(const rt_scene *s, int k, const rt_ray *ray, double a, double b, rt_span *out, int max)
{
    const rt_node *n = &s->nodes[k];
    double r[IG_MAX_DEGREE + 2], x[IG_MAX_DEGREE + 2];
    int f0 = 0, f1 = 0, nr, nx;
    rt_end ends[2];
    leaf_ray lr;
    leaf_ray_of(n, ray, &lr);
    if (!rt_clip_slabs(n->obox, lr.o, lr.d, lr.inv, &a, &b, &f0, &f1))
        return 0;
    if (!(b > a))
        return 0;
    if (!n->identity) {
        lr.L = ig_unit_vector(lr.d, lr.own_u); /* o, d: already in the leaf's object space */
        lr.u = lr.own_u;
    } else {
        lr.u = rt_ray_unit(ray, lr.own_u);
    }
    nr = (lr.L > 0.0 && isfinite(lr.L)) ? leaf_roots_unit(s, k, n, lr.o, lr.u, lr.L, a, b, r) : 0;
    ends[0].leaf = f0 ? k : -1; /* a box face, or open where the ray's range starts inside */
    ends[1].leaf = f1 ? k : -1;
    nx = leaf_breakpoints(r, nr, a, b, &f0, &f1, x);
    ends[0].t = a;
    ends[0].face = f0;
    ends[1].t = b;
    ends[1].face = f1;
    return spans_by_sign(n, k, &lr, x, nx, ends, out, max);
}

static int op_state(int op, int in_a, int in_b)
{
    switch (op) {
    case RT_UNION:
        return in_a || in_b;
    case RT_INTERSECTION:
        return in_a && in_b;
    default:
        return in_a && !in_b; /* difference: A and not B */
    }
}

/* One sweep over the endpoints of two sorted, disjoint span lists. Where the result's state changes the
 * endpoint that caused it is kept, so each result boundary remembers its surface. Spans that touch are
 * merged (no phantom boundary inside a union). */
static int combine(int op, const rt_span *A, int na, const rt_span *B, int nb, rt_span *out, int max)
{
    int ia = 0, ib = 0, in_a = 0, in_b = 0, in_o = 0, n = 0;
    rt_end start = {0.0, -1, 0};
    while (ia < 2 * na || ib < 2 * nb) {
        const rt_end *ea = ia < 2 * na ? ((ia & 1) ? &A[ia >> 1].out : &A[ia >> 1].in) : NULL;
        const rt_end *eb = ib < 2 * nb ? ((ib & 1) ? &B[ib >> 1].out : &B[ib >> 1].in) : NULL;
        const rt_end *e;
        int now;
        if (!eb || (ea && ea->t <= eb->t)) {
            e = ea;
            ++ia;
            in_a = !in_a;
        } else {
            e = eb;
            ++ib;
            in_b = !in_b;
        }
        now = op_state(op, in_a, in_b);
        if (now && !in_o) {
            if (n > 0 && out[n - 1].out.t >= e->t) {
                start = out[--n].in; /* touches the previous span: reopen it */
            } else {
                start = *e;
            }
        } else if (!now && in_o) {
            if (e->t > start.t && n < max) {
                out[n].in = start;
                out[n].out = *e;
                ++n;
            }
        }
        in_o = now;
    }
    return n;
}

int rt_spans(const rt_scene *s, int k, const rt_ray *ray, double a, double b, rt_span *out, int max)
{
    const rt_node *n = &s->nodes[k];
    rt_span L[RT_MAX_SPANS], R[RT_MAX_SPANS];
    int nl, nr;
    if (n->kind == RT_LEAF)
        return leaf_spans(s, k, ray, a, b, out, max);
    /* The node's box bounds everything below it (an unbounded leaf inside an intersection included); an open
     * side clips nothing. */
    if (!rt_clip_slabs(n->wbox, ray->o, ray->d, ray->inv, &a, &b, NULL, NULL))
        return 0;
    nl = rt_spans(s, n->left, ray, a, b, L, RT_MAX_SPANS);
    if (nl == 0 && n->kind != RT_UNION)
        return 0;
    nr = rt_spans(s, n->right, ray, a, b, R, RT_MAX_SPANS);
    if (nr == 0) {
        if (n->kind == RT_INTERSECTION)
            return 0;
        if (nl > max)
            nl = max;
        memcpy(out, L, (size_t)nl * sizeof *L);
        return nl;
    }
    return combine(n->kind, L, nl, R, nr, out, max);
}

int rt_node_spans(const rt_scene *s, int node, const double o[3], const double d[3], double tmin, double tmax,
                  double *t_in, double *t_out, int *leaf_in, int *leaf_out, int max)
{
    rt_span sp[RT_MAX_SPANS];
    rt_ray ray;
    int n, i;
    if (!s->committed || node < 0 || node >= s->nnodes)
        return 0;
    if (tmax > s->far)
        tmax = s->far;
    rt_ray_init(&ray, o, d, s->far, 1);
    n = rt_spans(s, node, &ray, tmin, tmax, sp, RT_MAX_SPANS);
    if (n > max)
        n = max;
    for (i = 0; i < n; ++i) {
        t_in[i] = sp[i].in.t;
        t_out[i] = sp[i].out.t;
        if (leaf_in)
            leaf_in[i] = sp[i].in.leaf;
        if (leaf_out)
            leaf_out[i] = sp[i].out.leaf;
    }
    return n;
}

/* A top-level leaf's surface hit at t, before rt_finish_hit works out its normal and side. */
static void surface_hit(rt_pending *hit, int leaf, double t)
{
    hit->t = t;
    hit->leaf = leaf;
    hit->face = 0;
    hit->entering = 0;
    hit->entering_known = 0;
}

/* A plane: a top-level leaf of degree 1 without bounds, the ground of most scenes. Along the ray f is
 * c0 + c1 t, with one root t = -c0 / c1, so the general solve's set-up is skipped: no unit direction (the
 * quotient does not depend on the direction's length, so the world parameter t comes out directly, with one
 * division), no shift point (for a line it gains nothing: f(o) is rounded relative to |grad f| |o|, as
 * o + t d itself is), no solver call chain. 1: a hit in (tmin, tmax) and [lo, hi]; 0: no hit; -1: a
 * coefficient not finite or c1 not a normal number -- the general path decides. s: for the floor report's
 * record. */
static int plane_hit(const rt_scene *s, const rt_node *n, int k, const rt_ray *ray, double tmin, double tmax, double lo,
                     double hi, rt_pending *hit)
{
    double oo[3], od[3], c[2], t;
    const double *po = ray->o, *pd = ray->d;
    (void)s;
    if (!n->identity) {
        rt_xform_point(n->minv, ray->o, oo);
        rt_xform_vector(n->minv, ray->d, od);
        po = oo;
        pd = od;
    }
    n->shape->coeffs(po, pd, n->params, c);
    if (!(fabs(c[0]) <= DBL_MAX) || !(fabs(c[1]) >= DBL_MIN && fabs(c[1]) <= DBL_MAX))
        return -1;
    t = -c[0] / c[1];
    if (!(t > tmin && t < tmax && t >= lo && t <= hi)) {
        RT_TRACE_SOLVE(s, k, po, pd, lo, hi, RT_TRACE_PLANE, 0, &t);
        return 0;
    }
    RT_TRACE_SOLVE(s, k, po, pd, lo, hi, RT_TRACE_PLANE, 1, &t);
    surface_hit(hit, k, t);
    hit->noise_known = 1; /* the expansion c0 + c1 t around the ray's origin, as rt_expansion_noise sums it */
    hit->noise_sum = fabs(c[1]) * fabs(t) + fabs(c[0]);
    hit->noise_val = c[1] * t + c[0];
    return 1;
}

/* Narrows [*lo, *hi] (in t) to where the ray p + s u, s = t L, is inside the leaf's clip region: 0 when that is
 * empty. The ball: |p + s u - c|^2 = r^2 with u a unit vector; the cube: its three slabs. */
static inline int clip_range(const rt_node *n, const double *p, const double *u, double L, double *lo, double *hi)
{
    double s0 = -INFINITY, s1 = INFINITY;
    if (n->clip == RT_CLIP_SPHERE) {
        double q[3], b, c, disc, h;
        int a;
        for (a = 0; a < 3; ++a)
            q[a] = p[a] - n->clip_c[a];
        b = rt_dot(q, u);
        c = rt_dot(q, q) - n->clip_r * n->clip_r;
        disc = b * b - c;
        if (!(disc > 0.0))
            return 0;
        h = sqrt(disc);
        s0 = -b - h;
        s1 = -b + h;
    } else {
        double cube[6];
        int a;
        for (a = 0; a < 3; ++a) {
            cube[a] = n->clip_c[a] - n->clip_r;
            cube[a + 3] = n->clip_c[a] + n->clip_r;
        }
        if (!rt_clip_box(cube, p, u, &s0, &s1, NULL, NULL))
            return 0;
    }
    *lo = fmax(*lo, s0 / L);
    *hi = fmin(*hi, s1 / L);
    return *hi > *lo;
}

/* The roots (in s = t L) among which the leaf's hit is the first in (tmin, tmax). The solver stops at the first
 * root in [lo, hi] (with any, at any point of the piece that holds it); only when that one cannot be used -- a
 * root exactly at tmin, or an unrefined point at an end -- are all of them needed. ex: NULL, or receives the
 * solve's expansion. */
static inline int leaf_solve(const rt_node *n, const double *po, const double *pu, double L, double tmin, double tmax,
                             double lo, double hi, int any, double *r, ig_shape_expansion *ex)
{
    int nr = ig_shape_solve(n->shape, n->params, &n->prep, po, pu, lo * L, hi * L, IG_ROOTS_AUTO,
                            any ? IG_ANY_ROOT : IG_FIRST_ROOT, r, ex);
    if (nr && (!(r[0] / L > tmin) || (any && !(r[0] / L < tmax))))
        nr = ig_shape_solve(n->shape, n->params, &n->prep, po, pu, lo * L, hi * L, IG_ROOTS_AUTO, IG_ALL_ROOTS, r, ex);
    return nr;
}

/* The first of the roots r (in s = t L) with tmin < t < tmax, as the leaf's pending hit; ex: the solve's
 * expansion, or NULL for an opaque shadow ray's yes/no solve (its hit is never finished). */
static inline int first_root_hit(const rt_node *n, int k, const double *r, int nr, double L, double tmin, double tmax,
                                 const ig_shape_expansion *ex, rt_pending *hit)
{
    int i;
    for (i = 0; i < nr; ++i) {
        double t = r[i] / L;
        if (t > tmin && t < tmax) {
            surface_hit(hit, k, t);
            hit->noise_known = ex != NULL;
            if (ex)
                rt_expansion_noise(ex, n->prep.degree, r[i], &hit->noise_sum, &hit->noise_val);
            return 1;
        }
    }
    return 0;
}

/* A CSG object's hit: the first end of its inside-intervals in (tmin, tmax) that lies on a surface (an end is
 * open where the ray's range starts or ends inside), the ray entering there or leaving. */
static inline int csg_hit(const rt_scene *s, int k, const rt_ray *ray, double tmin, double tmax, double lo, double hi,
                          rt_pending *hit)
{
    rt_span sp[RT_MAX_SPANS];
    int ns = rt_spans(s, k, ray, lo, hi, sp, RT_MAX_SPANS), i;
    for (i = 0; i < ns; ++i) {
        const rt_end *e = NULL;
        if (sp[i].in.t > tmin && sp[i].in.t < tmax && sp[i].in.leaf >= 0) {
            e = &sp[i].in;
            hit->entering = 1;
        } else if (sp[i].out.t > tmin && sp[i].out.t < tmax && sp[i].out.leaf >= 0) {
            e = &sp[i].out;
            hit->entering = 0;
        }
        if (e) {
            hit->t = e->t;
            hit->leaf = e->leaf;
            hit->face = e->face;
            hit->entering_known = 1;
            return 1;
        }
    }
    return 0;
}

int rt_object_hit(const rt_scene *s, int object, const rt_ray *ray, double tmin, double tmax, int any, rt_pending *hit)
{
    int k = s->objects[object], nr;
    const rt_node *n = &s->nodes[k];
    double lo = tmin, hi = tmax, oo[3], u[3], L = ray->len, r[IG_MAX_DEGREE + 2];
    const double *po = ray->o, *pu;
    ig_shape_expansion ex, *ex_wanted;
    /* A bounded object needs no clip to its world box here: the BVH has clipped the ray to a box around it,
     * a CSG root clips to its own box first thing in rt_spans, and a leaf's solve clips to the object-space box,
     * which the world box contains with room (its corners transformed, then padded by 1e-9 of its size). An
     * unbounded one is solved up to `far` (rt_scene_far). */
    if (!n->wbounded) {
        if (hi > ray->far_t)
            hi = ray->far_t;
        if (!(hi > lo))
            return 0;
    }
    hit->object = object;
    hit->noise_known = 0;
    if (n->kind != RT_LEAF)
        return csg_hit(s, k, ray, tmin, tmax, lo, hi, hit);
    /* A top-level leaf is a surface: its hit is the nearest root after tmin, solved along the unit object-space
     * direction (see rt_leaf_roots); an identity leaf takes the ray's own. */
    if (n->prep.degree == 1 && !n->prep.bounded && n->clip == RT_CLIP_NONE) {
        int got = plane_hit(s, n, k, ray, tmin, tmax, lo, hi, hit);
        if (got >= 0)
            return got;
    }
    if (!n->identity) {
        L = ig_affine_unit_ray(n->minv, ray->o, ray->d, oo, u);
        po = oo;
        pu = u;
    } else {
        pu = rt_ray_unit(ray, u);
    }
    if (!(L > 0.0) || !isfinite(L))
        return 0;
    if (n->clip != RT_CLIP_NONE && !clip_range(n, po, pu, L, &lo, &hi))
        return 0;
    /* An opaque shadow ray only asks whether there is a hit: the root need not be refined, nor its expansion
     * kept (an opaque shadow hit is never finished). */
    if (any && !rt_leaf_opaque(s, n))
        any = 0;
    ex_wanted = any ? NULL : &ex;
    nr = leaf_solve(n, po, pu, L, tmin, tmax, lo, hi, any, r, ex_wanted);
    RT_TRACE_SOLVE(s, k, po, pu, lo * L, hi * L, any ? IG_ANY_ROOT : IG_FIRST_ROOT, nr, r);
    return first_root_hit(n, k, r, nr, L, tmin, tmax, ex_wanted, hit);
}
