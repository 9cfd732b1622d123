/* Scene building, transforms, bounding boxes, the BVH over objects, and the closest-hit query.
 *
 * A scene is a flat array of nodes (leaves and CSG operators) plus the list of top-level objects. Objects
 * whose world box is finite go into a BVH; unbounded ones (a ground plane, an infinite cylinder) are kept in
 * a separate list and tested for every ray, solved along [tmin, far] where `far` stands in for infinity.
 */
#include "tracer_internal.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ small helpers */

void rt_xform_point(const double m[12], const double p[3], double out[3])
{
    double r[3];
    int i;
    for (i = 0; i < 3; ++i) r[i] = m[4 * i] * p[0] + m[4 * i + 1] * p[1] + m[4 * i + 2] * p[2] + m[4 * i + 3];
    memcpy(out, r, sizeof r);
}

void rt_xform_vector(const double m[12], const double v[3], double out[3])
{
    double r[3];
    int i;
    for (i = 0; i < 3; ++i) r[i] = m[4 * i] * v[0] + m[4 * i + 1] * v[1] + m[4 * i + 2] * v[2];
    memcpy(out, r, sizeof r);
}

void rt_to_object(const rt_node *n, const double o[3], const double d[3], double oo[3], double od[3])
{
    if (n->identity) {
        memcpy(oo, o, 3 * sizeof(double));
        memcpy(od, d, 3 * sizeof(double));
    } else {
        rt_xform_point(n->minv, o, oo);
        rt_xform_vector(n->minv, d, od);
    }
}

void rt_ray_init(rt_ray *r, const double o[3], const double d[3], double far)
{
    int a;
    memcpy(r->o, o, sizeof r->o);
    memcpy(r->d, d, sizeof r->d);
    r->len = sqrt(rt_dot(d, d));
    for (a = 0; a < 3; ++a) r->inv[a] = d[a] != 0.0 ? 1.0 / d[a] : 0.0;
    if (r->len > 0.0) {
        for (a = 0; a < 3; ++a) r->u[a] = d[a] / r->len;
        r->far_t = far / r->len;
    } else {
        r->u[0] = r->u[1] = r->u[2] = 0.0;
        r->far_t = INFINITY;
    }
}

static double maxabs3(const double v[3])
{
    double a = fabs(v[0]), b = fabs(v[1]), c = fabs(v[2]);
    return a > b ? (a > c ? a : c) : (b > c ? b : c);
}

static int grow(void **arr, int *cap, int need, size_t elem)
{
    void *p;
    int ncap;
    if (need <= *cap) return 1;
    ncap = *cap ? *cap * 2 : 16;
    while (ncap < need) ncap *= 2;
    p = realloc(*arr, (size_t)ncap * elem);
    if (!p) return 0;
    *arr = p;
    *cap = ncap;
    return 1;
}

static int fail(rt_scene *s, const char *msg)
{
    snprintf(s->error, sizeof s->error, "%s", msg);
    return -1;
}

/* Inverse of an affine 3x4 map. Returns 0 when the linear part is singular (relative to its size). */
static int invert_affine(const double m[12], double inv[12])
{
    double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], k = m[10];
    double c00 = e * k - f * h, c01 = c * h - b * k, c02 = b * f - c * e;
    double c10 = f * g - d * k, c11 = a * k - c * g, c12 = c * d - a * f;
    double c20 = d * h - e * g, c21 = b * g - a * h, c22 = a * e - b * d;
    double det = a * c00 + b * c10 + c * c20;
    double scale = 0.0, t[3];
    int i;
    for (i = 0; i < 12; ++i)
        if (i % 4 != 3 && fabs(m[i]) > scale) scale = fabs(m[i]);
    if (!(scale > 0.0) || !isfinite(det) || fabs(det) <= 1e-12 * scale * scale * scale) return 0;
    inv[0] = c00 / det; inv[1] = c01 / det; inv[2] = c02 / det;
    inv[4] = c10 / det; inv[5] = c11 / det; inv[6] = c12 / det;
    inv[8] = c20 / det; inv[9] = c21 / det; inv[10] = c22 / det;
    inv[3] = inv[7] = inv[11] = 0.0;
    t[0] = m[3]; t[1] = m[7]; t[2] = m[11];
    rt_xform_vector(inv, t, t);
    inv[3] = -t[0]; inv[7] = -t[1]; inv[11] = -t[2];
    return 1;
}

/* Slab clipping of [*t0, *t1] against an axis-aligned box (sides may be infinite). f0/f1 receive the
 * outward face code +-(axis + 1) of the face that moved the bound, or keep their value when the bound did
 * not move. Returns 1 when the clipped interval is non-empty. */
int rt_clip_box(const double box[6], const double o[3], const double d[3], double *t0, double *t1, int *f0,
                int *f1)
{
    double lo = *t0, hi = *t1;
    int a;
    for (a = 0; a < 3; ++a) {
        double bmin = box[a], bmax = box[a + 3];
        if (!(bmin <= bmax)) return 0; /* empty or NaN box */
        if (d[a] == 0.0) {
            if (!(o[a] >= bmin && o[a] <= bmax)) return 0;
            continue;
        } else {
            double inv = 1.0 / d[a], ta = (bmin - o[a]) * inv, tb = (bmax - o[a]) * inv;
            int fa = -(a + 1), fb = a + 1; /* outward normal of the min / max face */
            if (ta > tb) {
                double tt = ta;
                int ff = fa;
                ta = tb; tb = tt;
                fa = fb; fb = ff;
            }
            if (ta > lo) {
                lo = ta;
                if (f0) *f0 = fa;
            }
            if (tb < hi) {
                hi = tb;
                if (f1) *f1 = fb;
            }
            if (!(lo <= hi)) return 0;
        }
    }
    *t0 = lo;
    *t1 = hi;
    return 1;
}

/* ------------------------------------------------------------------ building */

rt_scene *rt_scene_new(void)
{
    rt_scene *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->eye[2] = 5.0;
    s->up[1] = 1.0;
    s->vfov = 40.0;
    return s;
}

void rt_scene_free(rt_scene *s)
{
    int i;
    if (!s) return;
    for (i = 0; i < s->nnodes; ++i) free(s->nodes[i].params);
    free(s->nodes);
    free(s->objects);
    free(s->materials);
    free(s->lights);
    free(s->unbounded);
    free(s->flat);
    free(s->order);
    free(s->bvh);
    free(s);
}

const char *rt_scene_error(const rt_scene *s) { return s->error; }

int rt_scene_add_material(rt_scene *s, const double *v)
{
    rt_material *m;
    int i;
    if (s->committed) return fail(s, "scene already committed");
    for (i = 0; i < RT_MATERIAL_DOUBLES; ++i)
        if (!isfinite(v[i])) return fail(s, "material value is not finite");
    if (!grow((void **)&s->materials, &s->cap_materials, s->nmaterials + 1, sizeof *s->materials))
        return fail(s, "out of memory");
    m = &s->materials[s->nmaterials];
    memcpy(m->color, v, 3 * sizeof(double));
    memcpy(m->color2, v + 3, 3 * sizeof(double));
    m->checker_scale = v[6];
    m->ambient = v[7];
    m->diffuse = v[8];
    m->specular = v[9];
    m->shininess = v[10];
    m->reflectivity = v[11];
    m->transparency = v[12];
    m->ior = v[13];
    memcpy(m->absorption, v + 14, 3 * sizeof(double));
    /* v[17], v[18] reserved (zero) */
    if (m->ior <= 0.0) return fail(s, "index of refraction must be positive");
    if (m->checker_scale < 0.0) return fail(s, "checker scale must be positive");
    return s->nmaterials++;
}

static int new_node(rt_scene *s)
{
    if (s->committed) return fail(s, "scene already committed");
    if (!grow((void **)&s->nodes, &s->cap_nodes, s->nnodes + 1, sizeof *s->nodes)) return fail(s, "out of memory");
    memset(&s->nodes[s->nnodes], 0, sizeof s->nodes[0]);
    return s->nnodes++;
}

int rt_scene_add_leaf(rt_scene *s, const ig_shape *shape, const double *params, int nparams,
                      const double *m, int material)
{
    rt_node *n;
    int i, k;
    if (!shape) return fail(s, "no shape");
    if (nparams != shape->nparams) return fail(s, "wrong number of shape parameters");
    if (material < 0 || material >= s->nmaterials) return fail(s, "leaf without a valid material");
    for (i = 0; i < 12; ++i)
        if (!isfinite(m[i])) return fail(s, "transform is not finite");
    for (i = 0; i < nparams; ++i)
        if (!isfinite(params[i])) return fail(s, "shape parameter is not finite");
    k = new_node(s);
    if (k < 0) return k;
    n = &s->nodes[k];
    n->kind = RT_LEAF;
    n->left = n->right = -1;
    n->material = material;
    n->shape = shape;
    n->params = malloc((size_t)(nparams > 0 ? nparams : 1) * sizeof(double));
    if (!n->params) {
        s->nnodes--;
        return fail(s, "out of memory");
    }
    if (nparams > 0) memcpy(n->params, params, (size_t)nparams * sizeof(double));
    memcpy(n->m, m, sizeof n->m);
    if (!invert_affine(n->m, n->minv)) {
        free(n->params);
        s->nnodes--;
        return fail(s, "transform is singular");
    }
    n->mnorm = 0.0;
    for (i = 0; i < 12; ++i)
        if (i % 4 != 3) n->mnorm += m[i] * m[i];
    n->mnorm = sqrt(n->mnorm);
    n->identity = 1;
    for (i = 0; i < 12; ++i)
        if (m[i] != ((i == 0 || i == 5 || i == 10) ? 1.0 : 0.0)) n->identity = 0;
    for (i = 0; i < 3; ++i) { /* what shape.c starts from too: an axis bounds() leaves alone is open */
        n->obox[i] = -INFINITY;
        n->obox[i + 3] = INFINITY;
    }
    n->obounded = shape->bounds ? shape->bounds(n->params, n->obox) : 0;
    ig_shape_prepare(shape, n->params, &n->prep);
    if (!n->obounded)
        for (i = 0; i < 3; ++i) {
            n->obox[i] = -INFINITY;
            n->obox[i + 3] = INFINITY;
        }
    return k;
}

int rt_scene_add_csg(rt_scene *s, int op, int left, int right, int material)
{
    rt_node *n;
    int k, dl, dr;
    if (op != RT_UNION && op != RT_INTERSECTION && op != RT_DIFFERENCE) return fail(s, "unknown CSG operation");
    if (left < 0 || left >= s->nnodes || right < 0 || right >= s->nnodes || left == right)
        return fail(s, "CSG child index out of range");
    if (material >= s->nmaterials) return fail(s, "material index out of range");
    dl = s->nodes[left].depth;
    dr = s->nodes[right].depth;
    if ((dl > dr ? dl : dr) + 1 > RT_MAX_CSG_DEPTH) return fail(s, "CSG nesting too deep");
    k = new_node(s);
    if (k < 0) return k;
    n = &s->nodes[k];
    n->kind = op;
    n->left = left;
    n->right = right;
    n->material = material;
    n->depth = (dl > dr ? dl : dr) + 1;
    n->mnorm = 1.0;
    return k;
}

int rt_scene_add_object(rt_scene *s, int node)
{
    if (s->committed) return fail(s, "scene already committed");
    if (node < 0 || node >= s->nnodes) return fail(s, "object node out of range");
    if (!grow((void **)&s->objects, &s->cap_objects, s->nobjects + 1, sizeof *s->objects))
        return fail(s, "out of memory");
    s->objects[s->nobjects] = node;
    return s->nobjects++;
}

int rt_scene_add_light(rt_scene *s, const double position[3], const double color[3])
{
    int i;
    if (s->committed) return fail(s, "scene already committed");
    for (i = 0; i < 3; ++i)
        if (!isfinite(position[i]) || !isfinite(color[i])) return fail(s, "light is not finite");
    if (!grow((void **)&s->lights, &s->cap_lights, 6 * (s->nlights + 1), sizeof *s->lights))
        return fail(s, "out of memory");
    memcpy(s->lights + 6 * s->nlights, position, 3 * sizeof(double));
    memcpy(s->lights + 6 * s->nlights + 3, color, 3 * sizeof(double));
    return s->nlights++;
}

void rt_scene_set_camera(rt_scene *s, const double eye[3], const double look_at[3], const double up[3],
                         double vfov)
{
    memcpy(s->eye, eye, sizeof s->eye);
    memcpy(s->look_at, look_at, sizeof s->look_at);
    memcpy(s->up, up, sizeof s->up);
    s->vfov = vfov;
}

void rt_scene_set_background(rt_scene *s, const double color[3]) { memcpy(s->background, color, sizeof s->background); }

/* ------------------------------------------------------------------ boxes and BVH */

static void pad_box(double b[6])
{
    double ext = 0.0, mag = 0.0, pad;
    int a;
    for (a = 0; a < 3; ++a) {
        if (b[a + 3] - b[a] > ext) ext = b[a + 3] - b[a];
        if (fabs(b[a]) > mag) mag = fabs(b[a]);
        if (fabs(b[a + 3]) > mag) mag = fabs(b[a + 3]);
    }
    /* Rounding in the corner transform is ~1e-16 relative; 1e-9 keeps the box conservative with room. */
    pad = 1e-9 * (ext + mag) + DBL_MIN;
    for (a = 0; a < 3; ++a) {
        b[a] -= pad;
        b[a + 3] += pad;
    }
}

static void node_box(rt_scene *s, int k)
{
    rt_node *n = &s->nodes[k];
    int a, i;
    if (n->kind == RT_LEAF) {
        n->wbounded = 0;
        if (!n->obounded) return;
        for (a = 0; a < 6; ++a)
            if (!isfinite(n->obox[a])) return;
        for (a = 0; a < 3; ++a) {
            n->wbox[a] = INFINITY;
            n->wbox[a + 3] = -INFINITY;
        }
        for (i = 0; i < 8; ++i) {
            double c[3], w[3];
            c[0] = n->obox[(i & 1) ? 3 : 0];
            c[1] = n->obox[(i & 2) ? 4 : 1];
            c[2] = n->obox[(i & 4) ? 5 : 2];
            rt_xform_point(n->m, c, w);
            for (a = 0; a < 3; ++a) {
                if (w[a] < n->wbox[a]) n->wbox[a] = w[a];
                if (w[a] > n->wbox[a + 3]) n->wbox[a + 3] = w[a];
            }
        }
        pad_box(n->wbox);
        n->wbounded = 1;
        return;
    }
    {
        const rt_node *l = &s->nodes[n->left], *r = &s->nodes[n->right];
        if (n->kind == RT_UNION) {
            n->wbounded = l->wbounded && r->wbounded;
            if (n->wbounded)
                for (a = 0; a < 3; ++a) {
                    n->wbox[a] = fmin(l->wbox[a], r->wbox[a]);
                    n->wbox[a + 3] = fmax(l->wbox[a + 3], r->wbox[a + 3]);
                }
        } else if (n->kind == RT_INTERSECTION) {
            n->wbounded = l->wbounded || r->wbounded;
            if (l->wbounded && r->wbounded) {
                for (a = 0; a < 3; ++a) {
                    n->wbox[a] = fmax(l->wbox[a], r->wbox[a]);
                    n->wbox[a + 3] = fmin(l->wbox[a + 3], r->wbox[a + 3]);
                }
            } else if (n->wbounded) {
                memcpy(n->wbox, l->wbounded ? l->wbox : r->wbox, sizeof n->wbox);
            }
        } else { /* difference: never larger than its left operand */
            n->wbounded = l->wbounded;
            if (n->wbounded) memcpy(n->wbox, l->wbox, sizeof n->wbox);
        }
    }
}

static int build_bvh(rt_scene *s, int first, int count)
{
    int k = s->nbvh++, a, i, axis = 0, mid;
    rt_bvh_node *b = &s->bvh[k];
    double cmin[3] = {INFINITY, INFINITY, INFINITY}, cmax[3] = {-INFINITY, -INFINITY, -INFINITY}, best = -1.0;
    for (a = 0; a < 3; ++a) {
        b->box[a] = INFINITY;
        b->box[a + 3] = -INFINITY;
    }
    for (i = first; i < first + count; ++i) {
        const double *w = s->nodes[s->objects[s->order[i]]].wbox;
        for (a = 0; a < 3; ++a) {
            double c = 0.5 * (w[a] + w[a + 3]);
            b->box[a] = fmin(b->box[a], w[a]);
            b->box[a + 3] = fmax(b->box[a + 3], w[a + 3]);
            cmin[a] = fmin(cmin[a], c);
            cmax[a] = fmax(cmax[a], c);
        }
    }
    b->first = first;
    b->count = count;
    b->left = b->right = -1;
    if (count <= 2) return k;
    for (a = 0; a < 3; ++a)
        if (cmax[a] - cmin[a] > best) {
            best = cmax[a] - cmin[a];
            axis = a;
        }
    /* Sort this range by centroid along the axis (insertion sort: object counts are small) and halve it. */
    for (i = first + 1; i < first + count; ++i) {
        int v = s->order[i], j = i - 1;
        const double *wv = s->nodes[s->objects[v]].wbox;
        double cv = wv[axis] + wv[axis + 3];
        while (j >= first) {
            const double *wj = s->nodes[s->objects[s->order[j]]].wbox;
            if (wj[axis] + wj[axis + 3] <= cv) break;
            s->order[j + 1] = s->order[j];
            --j;
        }
        s->order[j + 1] = v;
    }
    mid = count / 2;
    {
        int l = build_bvh(s, first, mid);
        int r = build_bvh(s, first + mid, count - mid);
        s->bvh[k].left = l;
        s->bvh[k].right = r;
        s->bvh[k].count = 0;
    }
    return k;
}

int rt_scene_commit(rt_scene *s)
{
    int i, a, nb = 0;
    double size = 0.0;
    if (s->committed) return 0;
    if (s->nmaterials == 0 && s->nobjects > 0) return fail(s, "no materials");
    for (i = 0; i < s->nnodes; ++i) node_box(s, i); /* children always precede parents */
    free(s->unbounded);
    free(s->flat);
    free(s->order);
    free(s->bvh);
    s->unbounded = malloc((size_t)(s->nobjects + 1) * sizeof(int));
    s->flat = malloc((size_t)(s->nobjects + 1));
    s->order = malloc((size_t)(s->nobjects + 1) * sizeof(int));
    s->bvh = malloc((size_t)(2 * s->nobjects + 1) * sizeof *s->bvh);
    if (!s->unbounded || !s->flat || !s->order || !s->bvh) return fail(s, "out of memory");
    s->nunbounded = 0;
    s->nbvh = 0;
    for (i = 0; i < s->nobjects; ++i) {
        const rt_node *n = &s->nodes[s->objects[i]];
        s->flat[i] = n->kind == RT_LEAF && n->shape->degree == 1;
        if (n->wbounded) {
            s->order[nb++] = i;
            for (a = 0; a < 6; ++a) size = fmax(size, fabs(n->wbox[a]));
        } else {
            s->unbounded[s->nunbounded++] = i;
        }
    }
    if (nb > 0) build_bvh(s, 0, nb);
    size = fmax(size, maxabs3(s->eye));
    size = fmax(size, maxabs3(s->look_at));
    for (i = 0; i < s->nlights; ++i) size = fmax(size, maxabs3(s->lights + 6 * i));
    if (!(size > 0.0) || !isfinite(size)) size = 1.0;
    s->far = 1e5 * size;
    s->committed = 1;
    return 0;
}

int rt_scene_count(const rt_scene *s, int what)
{
    switch (what) {
    case 0: return s->nnodes;
    case 1: return s->nobjects;
    case 2: return s->nunbounded;
    case 3: return s->nbvh;
    default: return -1;
    }
}

double rt_scene_far(const rt_scene *s) { return s->far; }

int rt_scene_node_box(const rt_scene *s, int node, double box[6])
{
    if (node < 0 || node >= s->nnodes || !s->nodes[node].wbounded) return 0;
    memcpy(box, s->nodes[node].wbox, 6 * sizeof(double));
    return 1;
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
static double solver_noise(const rt_node *n, const double oo[3], const double od[3], const double po[3], double fp,
                           double t)
{
    double c[IG_MAX_DEGREE + 1], os[3], num = 0.0, den = 0.0, ts, tau, pw = 1.0, sum = 0.0, horner = 0.0;
    int a, k, deg = n->shape->degree;
    for (k = 0; k < n->prep.nfinite; ++k) { /* the box's finite axes (none for an unbounded shape) */
        a = n->prep.finite[k];
        num += od[a] * (n->prep.centre[a] - oo[a]);
        den += od[a] * od[a];
    }
    if (!(den > 0.0)) {
        num = -rt_dot(oo, od);
        den = rt_dot(od, od);
    }
    ts = den > 0.0 ? num / den : 0.0;
    if (!isfinite(ts)) ts = 0.0;
    for (a = 0; a < 3; ++a) os[a] = oo[a] + ts * od[a];
    n->shape->coeffs(os, od, n->params, c);
    tau = t - ts;
    for (k = 0; k <= deg; ++k) {
        sum += fabs(c[k]) * pw;
        pw *= fabs(tau);
    }
    for (k = deg; k >= 0; --k) horner = horner * tau + c[k];
    /* The secondary ray will be solved from its own shift point, not this one; when this ray's shift point
     * happens to sit at the hit, the sum above sees only |f(po)| ~ 0. So also expand along the segment from
     * the box centre (the coordinate origin on open axes) to po: the noise any ray solved inside the box
     * meets near po. */
    {
        double seg[3], c2[IG_MAX_DEGREE + 1], sum2 = 0.0;
        for (a = 0; a < 3; ++a) seg[a] = po[a] - n->prep.centre[a];
        n->shape->coeffs(n->prep.centre, seg, n->params, c2);
        for (k = 0; k <= deg; ++k) sum2 += fabs(c2[k]);
        if (sum2 > sum) sum = sum2;
    }
    sum = RT_ERR_OBJECT * DBL_EPSILON * (double)(deg + 1) * sum;
    horner = RT_ERR_OBJECT * fabs(horner - fp);
    if (!isfinite(sum) || !isfinite(horner)) return 0.0;
    return sum > horner ? sum : horner;
}

/* How far from po the surface can be, given |f(po)| plus its noise: along the direction u (the normal, or
 * the ray at a singular point) f(po + s u) = c_0 + c_1 s + c_2 s^2 + ...; the smallest s at which one term
 * c_k s^k reaches |c_0| + noise. With k = 1 this is the familiar (|f| + noise) / |grad f|; the higher terms
 * keep the estimate finite where grad f vanishes (a cusp, or the heart's singular equator). */
static double distance_bound(const rt_node *n, const double po[3], const double u[3], double level)
{
    double c[IG_MAX_DEGREE + 1], best = INFINITY, best_pow = INFINITY;
    int k, deg = n->shape->degree;
    n->shape->coeffs(po, u, n->params, c);
    for (k = 1; k <= deg; ++k) {
        double q;
        if (k > 1 && isfinite(best)) best_pow *= best; /* best^k */
        if (!(c[k] != 0.0) || !isfinite(c[k])) continue;
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

void rt_finish_hit(const rt_scene *s, const rt_pending *pd, const double o[3], const double d[3], rt_hit *hit,
                   rt_hit_lazy *lazy)
{
    const rt_node *n = &s->nodes[pd->leaf];
    rt_hit_lazy own, *lz = lazy ? lazy : &own;
    double g[3], nw[3], len, t = pd->t;
    int a, singular = 0, face = pd->face, entering = pd->entering, entering_known = pd->entering_known;

    rt_to_object(n, o, d, lz->oo, lz->od);
    memcpy(lz->o, o, sizeof lz->o);
    memcpy(lz->d, d, sizeof lz->d);
    for (a = 0; a < 3; ++a) {
        hit->p[a] = o[a] + t * d[a];
        hit->po[a] = lz->oo[a] + t * lz->od[a];
        lz->u[a] = 0.0;
    }
    lz->f = 0.0;
    if (face == 0) {
        double f = n->shape->value(hit->po, n->params), gl;
        n->shape->gradient(hit->po, n->params, g);
        gl = sqrt(rt_dot(g, g));
        if (!(gl > 0.0) || !isfinite(gl) || !isfinite(f)) singular = 1;
        /* the direction rt_hit_error measures the distance to f = 0 along */
        if (!singular) {
            for (a = 0; a < 3; ++a) lz->u[a] = g[a] / gl;
        } else {
            double l = sqrt(rt_dot(lz->od, lz->od));
            for (a = 0; a < 3; ++a) lz->u[a] = lz->od[a] / l;
        }
        lz->f = f;
    } else {
        g[0] = g[1] = g[2] = 0.0;
        g[abs(face) - 1] = face > 0 ? 1.0 : -1.0;
    }
    /* World normal by the inverse transpose: n_w = Minv^T g. */
    if (!singular) {
        for (a = 0; a < 3; ++a) nw[a] = n->minv[a] * g[0] + n->minv[4 + a] * g[1] + n->minv[8 + a] * g[2];
        len = sqrt(rt_dot(nw, nw));
        if (!(len > 0.0) || !isfinite(len)) singular = 1;
        else
            for (a = 0; a < 3; ++a) nw[a] /= len;
    }
    if (singular) {
        /* grad f = 0 (a cusp, an apex): no normal exists; face the ray so shading stays finite. */
        len = sqrt(rt_dot(d, d));
        for (a = 0; a < 3; ++a) nw[a] = -d[a] / len;
        g[0] = g[1] = g[2] = 0.0;
        if (!entering_known) entering = 1;
    } else if (!entering_known) {
        entering = rt_dot(nw, d) < 0.0;
    } else if ((rt_dot(nw, d) < 0.0) != (entering != 0)) {
        /* CSG: orient by the interval end (this also flips a subtracted part's normal). */
        for (a = 0; a < 3; ++a) {
            nw[a] = -nw[a];
            g[a] = -g[a];
        }
    }
    memcpy(hit->n, nw, sizeof nw);
    len = sqrt(rt_dot(g, g));
    for (a = 0; a < 3; ++a) hit->no[a] = len > 0.0 ? g[a] / len : nw[a];
    hit->err = 0.0;
    hit->t = t;
    hit->object = pd->object;
    hit->leaf = pd->leaf;
    hit->face = face;
    hit->material = n->material;
    hit->entering = entering != 0;
    hit->singular = singular;
    lz->pending = 1;
    if (!lazy) rt_hit_error(s, hit, lz);
}

void rt_hit_error(const rt_scene *s, rt_hit *hit, rt_hit_lazy *lz)
{
    const rt_node *n = &s->nodes[hit->leaf];
    double dist = 0.0, mag_o, mag_w, td[3], tod[3], tr[3], t = hit->t;
    int a;
    if (!lz->pending) return;
    lz->pending = 0;
    if (hit->face == 0) {
        double f = lz->f, level;
        level = isfinite(f) ? fabs(f) + solver_noise(n, lz->oo, lz->od, hit->po, f, t) : 0.0;
        /* distance of the computed point from f = 0, including how far the solver's noise can move a root */
        dist = level > 0.0 ? distance_bound(n, hit->po, lz->u, level) : 0.0;
    }
    /* Error bound of the hit point, in world units. The object-space part: the measured distance |f|/|grad f|
     * of the computed point, plus the rounding noise of evaluating f and of forming o' + t d' (relative to
     * the magnitudes involved); M stretches it by at most its norm. The world part: rounding of o + t d and
     * of the transforms. */
    for (a = 0; a < 3; ++a) {
        td[a] = t * lz->d[a];
        tod[a] = t * lz->od[a];
    }
    mag_o = maxabs3(lz->oo) + maxabs3(tod) + maxabs3(hit->po);
    tr[0] = n->m[3];
    tr[1] = n->m[7];
    tr[2] = n->m[11];
    mag_w = maxabs3(lz->o) + maxabs3(td) + maxabs3(hit->p) + maxabs3(tr);
    hit->err = n->mnorm * (dist + RT_ERR_OBJECT * DBL_EPSILON * (double)(n->shape->degree + 1) * mag_o) +
               RT_ERR_WORLD * DBL_EPSILON * mag_w;
}

/* Slab test of the ray against an axis-aligned box, as rt_clip_box (same arithmetic) without face codes. */
static int ray_box(const double box[6], const rt_ray *r, double *t0, double *t1)
{
    double lo = *t0, hi = *t1;
    int a;
    for (a = 0; a < 3; ++a) {
        double bmin = box[a], bmax = box[a + 3];
        if (!(bmin <= bmax)) return 0; /* empty or NaN box */
        if (r->d[a] == 0.0) {
            if (!(r->o[a] >= bmin && r->o[a] <= bmax)) return 0;
        } else {
            double ta = (bmin - r->o[a]) * r->inv[a], tb = (bmax - r->o[a]) * r->inv[a];
            if (ta > tb) {
                double tt = ta;
                ta = tb;
                tb = tt;
            }
            if (ta > lo) lo = ta;
            if (tb < hi) hi = tb;
            if (!(lo <= hi)) return 0;
        }
    }
    *t0 = lo;
    *t1 = hi;
    return 1;
}

int rt_spawn_skip(const rt_scene *s, const rt_hit *h) { return s->flat[h->object] ? h->object : -1; }

int rt_scene_closest(const rt_scene *s, const double o[3], const double d[3], double tmin, double tmax, int mode,
                     int skip, rt_pending *out)
{
    double best = tmax;
    int found = 0, i, sp = 0;
    int stack[128];
    double entry[128];
    rt_ray ray;
    rt_pending h;
    if (!s->committed) return 0;
    if (!isfinite(d[0]) || !isfinite(d[1]) || !isfinite(d[2]) || !isfinite(o[0]) || !isfinite(o[1]) ||
        !isfinite(o[2]))
        return 0;
    rt_ray_init(&ray, o, d, s->far);
    /* A hit is kept when it is closer than the best so far (rt_object_hit only reports t < best). In
     * RT_ANY_OPAQUE mode a hit on an opaque material ends the search. */
#define RT_TAKE(obj)                                                                                             \
    if ((obj) != skip && rt_object_hit(s, (obj), &ray, tmin, best, &h)) {                                       \
        *out = h;                                                                                                \
        best = h.t;                                                                                              \
        found = 1;                                                                                               \
        if (mode == RT_ANY_OPAQUE && s->materials[s->nodes[h.leaf].material].transparency <= 0.0) return 1;    \
    }
    for (i = 0; i < s->nunbounded; ++i) RT_TAKE(s->unbounded[i])
    /* Each stack entry carries the t where the ray enters its box, so a node is clipped once and skipped
     * when a closer hit has been found since it was pushed. */
    if (s->nbvh > 0) {
        double t0 = tmin, t1 = best;
        if (ray_box(s->bvh[0].box, &ray, &t0, &t1)) {
            stack[sp] = 0;
            entry[sp++] = t0;
        }
    }
    while (sp > 0) {
        const rt_bvh_node *b;
        --sp;
        if (entry[sp] > best) continue;
        b = &s->bvh[stack[sp]];
        if (b->left < 0) {
            for (i = b->first; i < b->first + b->count; ++i) RT_TAKE(s->order[i])
        } else if (sp + 2 <= (int)(sizeof stack / sizeof stack[0])) {
            /* visit the nearer child first: push it last */
            const rt_bvh_node *l = &s->bvh[b->left], *r = &s->bvh[b->right];
            double la = tmin, lb = best, ra = tmin, rb = best;
            int lhit = ray_box(l->box, &ray, &la, &lb);
            int rhit = ray_box(r->box, &ray, &ra, &rb);
            if (lhit && rhit && la > ra) {
                stack[sp] = b->left;
                entry[sp++] = la;
                stack[sp] = b->right;
                entry[sp++] = ra;
            } else {
                if (rhit) {
                    stack[sp] = b->right;
                    entry[sp++] = ra;
                }
                if (lhit) {
                    stack[sp] = b->left;
                    entry[sp++] = la;
                }
            }
        }
    }
#undef RT_TAKE
    return found;
}

int rt_scene_intersect(const rt_scene *s, const double o[3], const double d[3], double tmin, double tmax,
                       rt_hit *hit)
{
    rt_pending h;
    if (!rt_scene_closest(s, o, d, tmin, tmax, RT_CLOSEST, -1, &h)) return 0;
    rt_finish_hit(s, &h, o, d, hit, NULL);
    return 1;
}
