/* Scene building: transforms, materials, leaves and CSG nodes, bounding boxes, and the BVH over objects.
 *
 * A scene is a flat array of nodes (leaves and CSG operators) plus the list of top-level objects. Objects
 * whose world box is finite go into a BVH; unbounded ones (a ground plane, an infinite cylinder) are kept in
 * a separate list and tested for every ray, solved along [tmin, far] where `far` stands in for infinity. The
 * queries against a committed scene are in tracer_hit.c.
 */
#include "tracer_internal.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ small helpers */

void rt_xform_point(const double m[12], const double p[3], double out[3]) { ig_affine_point(m, p, out); }

void rt_xform_vector(const double m[12], const double v[3], double out[3]) { ig_affine_vector(m, v, out); }

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

static int grow(void **arr, int *cap, int need, size_t elem)
{
    void *p;
    int ncap;
    if (need <= *cap)
        return 1;
    ncap = *cap ? *cap * 2 : 16;
    while (ncap < need)
        ncap *= 2;
    p = realloc(*arr, (size_t)ncap * elem);
    if (!p)
        return 0;
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
/* ------------------------------------------------------------------ building */

rt_scene *rt_scene_new(void)
{
    rt_scene *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    s->eye[2] = 5.0;
    s->up[1] = 1.0;
    s->vfov = 40.0;
    return s;
}

void rt_scene_free(rt_scene *s)
{
    int i;
    if (!s)
        return;
    for (i = 0; i < s->nnodes; ++i)
        free(s->nodes[i].params);
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
    if (s->committed)
        return fail(s, "scene already committed");
    for (i = 0; i < RT_MATERIAL_DOUBLES; ++i)
        if (!isfinite(v[i]))
            return fail(s, "material value is not finite");
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
    m->two_sided = v[17];
    memcpy(m->inside, v + 18, 3 * sizeof(double));
    if (m->two_sided != 0.0 && m->two_sided != 1.0)
        return fail(s, "two_sided must be 0 or 1");
    if (m->ior <= 0.0)
        return fail(s, "index of refraction must be positive");
    if (m->checker_scale < 0.0)
        return fail(s, "checker scale must be positive");
    return s->nmaterials++;
}

static int new_node(rt_scene *s)
{
    if (s->committed)
        return fail(s, "scene already committed");
    if (!grow((void **)&s->nodes, &s->cap_nodes, s->nnodes + 1, sizeof *s->nodes))
        return fail(s, "out of memory");
    memset(&s->nodes[s->nnodes], 0, sizeof s->nodes[0]);
    return s->nnodes++;
}

/* Why a leaf's arguments cannot make a leaf, or NULL. */
static const char *leaf_refusal(const rt_scene *s, const ig_shape *shape, const double *params, int nparams,
                                const double *m, int material)
{
    int i;
    if (!shape)
        return "no shape";
    if (nparams != shape->nparams)
        return "wrong number of shape parameters";
    if (material < 0 || material >= s->nmaterials)
        return "leaf without a valid material";
    for (i = 0; i < 12; ++i)
        if (!isfinite(m[i]))
            return "transform is not finite";
    for (i = 0; i < nparams; ++i)
        if (!isfinite(params[i]))
            return "shape parameter is not finite";
    return NULL;
}

/* The leaf's transform, set and checked: its inverse (0 when it is singular), its linear part's Frobenius norm,
 * whether it is the identity. */
static int leaf_transform(rt_node *n, const double *m)
{
    int i;
    memcpy(n->m, m, sizeof n->m);
    if (!ig_affine_invert(n->m, n->minv))
        return 0;
    n->mnorm = 0.0;
    for (i = 0; i < 12; ++i)
        if (i % 4 != 3)
            n->mnorm += m[i] * m[i];
    n->mnorm = sqrt(n->mnorm);
    n->identity = 1;
    for (i = 0; i < 12; ++i)
        if (m[i] != ((i == 0 || i == 5 || i == 10) ? 1.0 : 0.0))
            n->identity = 0;
    return 1;
}

/* The leaf's object box (open on an axis bounds() leaves alone, everywhere when the shape is not bounded), its
 * prepared solve, and the half-size of its finite axes. */
static void leaf_object_box(rt_node *n, const ig_shape *shape)
{
    int i;
    for (i = 0; i < 3; ++i) { /* what shape.c starts from too: an axis bounds() leaves alone is open */
        n->obox[i] = -INFINITY;
        n->obox[i + 3] = INFINITY;
    }
    n->obounded = shape->bounds ? shape->bounds(n->params, n->obox) : 0;
    ig_shape_prepare(shape, n->params, &n->prep);
    n->half = 0.0;
    for (i = 0; i < n->prep.nfinite; ++i) {
        int a = n->prep.finite[i];
        n->half = fmax(n->half, 0.5 * (n->prep.hi[a] - n->prep.lo[a]));
    }
    if (!n->obounded)
        for (i = 0; i < 3; ++i) {
            n->obox[i] = -INFINITY;
            n->obox[i + 3] = INFINITY;
        }
}

int rt_scene_add_leaf(rt_scene *s, const ig_shape *shape, const double *params, int nparams, const double *m,
                      int material)
{
    const char *why = leaf_refusal(s, shape, params, nparams, m, material);
    rt_node *n;
    int k;
    if (why)
        return fail(s, why);
    k = new_node(s);
    if (k < 0)
        return k;
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
    if (nparams > 0)
        memcpy(n->params, params, (size_t)nparams * sizeof(double));
    if (!leaf_transform(n, m)) {
        free(n->params);
        s->nnodes--;
        return fail(s, "transform is singular");
    }
    leaf_object_box(n, shape);
    return k;
}

int rt_scene_add_csg(rt_scene *s, int op, int left, int right, int material)
{
    rt_node *n;
    int k, dl, dr;
    if (op != RT_UNION && op != RT_INTERSECTION && op != RT_DIFFERENCE)
        return fail(s, "unknown CSG operation");
    if (left < 0 || left >= s->nnodes || right < 0 || right >= s->nnodes || left == right)
        return fail(s, "CSG child index out of range");
    if (material >= s->nmaterials)
        return fail(s, "material index out of range");
    if (s->nodes[left].clip != RT_CLIP_NONE || s->nodes[right].clip != RT_CLIP_NONE)
        return fail(s, "a clipped leaf cannot be a CSG operand");
    dl = s->nodes[left].depth;
    dr = s->nodes[right].depth;
    if ((dl > dr ? dl : dr) + 1 > RT_MAX_CSG_DEPTH)
        return fail(s, "CSG nesting too deep");
    k = new_node(s);
    if (k < 0)
        return k;
    n = &s->nodes[k];
    n->kind = op;
    n->left = left;
    n->right = right;
    n->material = material;
    n->depth = (dl > dr ? dl : dr) + 1;
    n->mnorm = 1.0;
    return k;
}

/* Whether a CSG node uses node k (nodes refer only to earlier ones, so only later nodes are looked at). */
static int is_operand(const rt_scene *s, int k)
{
    int i;
    for (i = k + 1; i < s->nnodes; ++i)
        if (s->nodes[i].kind != RT_LEAF && (s->nodes[i].left == k || s->nodes[i].right == k))
            return 1;
    return 0;
}

int rt_scene_set_clip(rt_scene *s, int node, int kind, const double center[3], double size)
{
    rt_node *n;
    if (s->committed)
        return fail(s, "scene already committed");
    if (node < 0 || node >= s->nnodes || s->nodes[node].kind != RT_LEAF)
        return fail(s, "a clip is for a leaf");
    n = &s->nodes[node];
    if (is_operand(s, node))
        return fail(s, "a clipped leaf cannot be a CSG operand");
    if (kind != RT_CLIP_NONE && kind != RT_CLIP_SPHERE && kind != RT_CLIP_BOX)
        return fail(s, "unknown clip kind");
    if (kind != RT_CLIP_NONE &&
        (!(size > 0.0) || !isfinite(size) || !isfinite(center[0]) || !isfinite(center[1]) || !isfinite(center[2])))
        return fail(s, "clip size must be finite and positive, its centre finite");
    n->clip = kind;
    memcpy(n->clip_c, center, sizeof n->clip_c);
    n->clip_r = size;
    return 0;
}

int rt_scene_add_object(rt_scene *s, int node)
{
    if (s->committed)
        return fail(s, "scene already committed");
    if (node < 0 || node >= s->nnodes)
        return fail(s, "object node out of range");
    if (!grow((void **)&s->objects, &s->cap_objects, s->nobjects + 1, sizeof *s->objects))
        return fail(s, "out of memory");
    s->objects[s->nobjects] = node;
    return s->nobjects++;
}

int rt_scene_add_light(rt_scene *s, const double position[3], const double color[3])
{
    int i;
    if (s->committed)
        return fail(s, "scene already committed");
    for (i = 0; i < 3; ++i)
        if (!isfinite(position[i]) || !isfinite(color[i]))
            return fail(s, "light is not finite");
    if (!grow((void **)&s->lights, &s->cap_lights, 6 * (s->nlights + 1), sizeof *s->lights))
        return fail(s, "out of memory");
    memcpy(s->lights + 6 * s->nlights, position, 3 * sizeof(double));
    memcpy(s->lights + 6 * s->nlights + 3, color, 3 * sizeof(double));
    return s->nlights++;
}

void rt_scene_set_camera(rt_scene *s, const double eye[3], const double look_at[3], const double up[3], double vfov)
{
    memcpy(s->eye, eye, sizeof s->eye);
    memcpy(s->look_at, look_at, sizeof s->look_at);
    memcpy(s->up, up, sizeof s->up);
    s->vfov = vfov;
}

void rt_scene_set_background(rt_scene *s, const double color[3]) { memcpy(s->background, color, sizeof s->background); }

/* ------------------------------------------------------------------ boxes and BVH */

/* The object-space box of what a leaf shows: the spec's box, cut by the clip region's (both kinds fit in the
 * cube of half-edge clip_r), so a clipped unbounded shape becomes a bounded object. 0 when neither bounds it. */
static int leaf_box(const rt_node *n, double box[6])
{
    int a;
    memcpy(box, n->obox, 6 * sizeof(double));
    if (n->clip != RT_CLIP_NONE)
        for (a = 0; a < 3; ++a) {
            box[a] = fmax(box[a], n->clip_c[a] - n->clip_r);
            box[a + 3] = fmin(box[a + 3], n->clip_c[a] + n->clip_r);
        }
    return n->obounded || n->clip != RT_CLIP_NONE;
}

/* A node's world box. Sides may be infinite: an intersection of a leaf bounded in x and z with one bounded in
 * y (the glassware's stem) is bounded all round, and goes into the BVH. */
static void node_box(rt_scene *s, int k)
{
    rt_node *n = &s->nodes[k];
    int a;
    if (n->kind == RT_LEAF) {
        double box[6];
        if (leaf_box(n, box)) {
            n->wbounded = ig_affine_box(n->m, box, n->wbox);
        } else {
            for (a = 0; a < 3; ++a) {
                n->wbox[a] = -INFINITY;
                n->wbox[a + 3] = INFINITY;
            }
            n->wbounded = 0;
        }
        return;
    }
    {
        const rt_node *l = &s->nodes[n->left], *r = &s->nodes[n->right];
        for (a = 0; a < 3; ++a) {
            if (n->kind == RT_UNION) {
                n->wbox[a] = fmin(l->wbox[a], r->wbox[a]);
                n->wbox[a + 3] = fmax(l->wbox[a + 3], r->wbox[a + 3]);
            } else if (n->kind == RT_INTERSECTION) {
                n->wbox[a] = fmax(l->wbox[a], r->wbox[a]);
                n->wbox[a + 3] = fmin(l->wbox[a + 3], r->wbox[a + 3]);
            } else { /* difference: never larger than its left operand */
                n->wbox[a] = l->wbox[a];
                n->wbox[a + 3] = l->wbox[a + 3];
            }
        }
        n->wbounded = 1;
        for (a = 0; a < 6; ++a)
            n->wbounded = n->wbounded && isfinite(n->wbox[a]);
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
    if (count <= 2)
        return k;
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
            if (wj[axis] + wj[axis + 3] <= cv)
                break;
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

/* Whether any leaf solves along the world ray's unit direction (rt_scene's unit_rays): an identity leaf under a CSG
 * node, or an identity top-level leaf that is not a plane the plane path takes (rt_object_hit). */
static int unit_rays_needed(const rt_scene *s)
{
    int i;
    for (i = 0; i < s->nnodes; ++i) {
        const rt_node *n = &s->nodes[i];
        if (n->kind != RT_LEAF) {
            if ((s->nodes[n->left].kind == RT_LEAF && s->nodes[n->left].identity) ||
                (s->nodes[n->right].kind == RT_LEAF && s->nodes[n->right].identity))
                return 1;
        }
    }
    for (i = 0; i < s->nobjects; ++i) {
        const rt_node *n = &s->nodes[s->objects[i]];
        if (n->kind == RT_LEAF && n->identity && !(n->prep.degree == 1 && !n->prep.bounded && n->clip == RT_CLIP_NONE))
            return 1;
    }
    return 0;
}

int rt_scene_commit(rt_scene *s)
{
    int i, a, nb = 0;
    double size = 0.0;
    if (s->committed)
        return 0;
    if (s->nmaterials == 0 && s->nobjects > 0)
        return fail(s, "no materials");
    for (i = 0; i < s->nnodes; ++i)
        node_box(s, i); /* children always precede parents */
    free(s->unbounded);
    free(s->flat);
    free(s->order);
    free(s->bvh);
    s->unbounded = malloc((size_t)(s->nobjects + 1) * sizeof(int));
    s->flat = malloc((size_t)(s->nobjects + 1));
    s->order = malloc((size_t)(s->nobjects + 1) * sizeof(int));
    s->bvh = malloc((size_t)(2 * s->nobjects + 1) * sizeof *s->bvh);
    if (!s->unbounded || !s->flat || !s->order || !s->bvh)
        return fail(s, "out of memory");
    s->nunbounded = 0;
    s->nbvh = 0;
    s->unit_rays = unit_rays_needed(s);
    for (i = 0; i < s->nobjects; ++i) {
        const rt_node *n = &s->nodes[s->objects[i]];
        s->flat[i] = n->kind == RT_LEAF && n->shape->degree == 1;
        if (n->wbounded) {
            s->order[nb++] = i;
            for (a = 0; a < 6; ++a)
                size = fmax(size, fabs(n->wbox[a]));
        } else {
            s->unbounded[s->nunbounded++] = i;
        }
    }
    if (nb > 0)
        build_bvh(s, 0, nb);
    size = fmax(size, rt_maxabs3(s->eye));
    size = fmax(size, rt_maxabs3(s->look_at));
    for (i = 0; i < s->nlights; ++i)
        size = fmax(size, rt_maxabs3(s->lights + 6 * i));
    if (!(size > 0.0) || !isfinite(size))
        size = 1.0;
    s->far = 1e5 * size;
    s->committed = 1;
    return 0;
}

double rt_scene_far(const rt_scene *s) { return s->far; }
