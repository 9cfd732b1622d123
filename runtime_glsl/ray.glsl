// implgen GLSL runtime: the first root of f along a ray, in float, with a flag where float cannot tell.
//
// GLSL has no function pointers, so the generated shape owns the loop and this file owns every decision:
//
//     IgRay ray = ig_ray_begin(o, d, tmin, tmax, lo, hi);           // clip to the box, shift the origin
//     for (int i = 0; i < IG_MAX_STEPS && ray.mode != IG_DONE; ++i) {
//         vec3 x, y, z;
//         ig_ray_query(ray, x, y, z);                                // the segment or point to bound
//         ig_ray_answer(ray, NAME_raa(x, y, z));                     // f over it, as an affine form
//     }
//     int status = ig_ray_finish(ray, t);                            // IG_HIT, IG_UNSURE bits
//
// The method (docs/glsl.md has the reasons and the failure modes):
//   1. The ray is clipped to the shape's box and to [tmin, tmax]; the origin moves to the middle of what
//      is left (t = tc + s), so the coordinates stay near the object and s stays small.
//   2. [s0, s1] is cut in halves, depth first, left to right, without a stack: a segment is (level, index),
//      and the next one comes from incrementing the index and dropping the trailing halvings.
//   3. On each segment f is bounded by reduced affine arithmetic over the shape's own expression (raa.glsl),
//      with every rounding error counted. A segment whose form excludes 0 holds no root and has the sign of
//      its centre. One that does not is halved, down to IG_MAX_DEPTH levels or to float resolution.
//   4. A segment at the bottom that still cannot be decided joins a "run" of such leaves. The sign of f is
//      certified at the start of the run (the end of an excluded segment, or a point bound) and at the end
//      of each leaf (a point bound). A certified change of sign proves a root: the ray hits, and the root
//      is refined by bisection inside the run. A run that ends with the sign it started with may hold no
//      root or two (a tangent, a thin sliver, or only rounding noise): if some float value in it had the
//      other sign, the answer is a hit there, flagged IG_UNSURE; otherwise the traversal goes on, and this
//      "doubt" is remembered. A doubt next to the run of a later certified root (within IG_MERGE of the
//      finest leaves) is the same stretch of noise around that root, cut in two by one segment that the
//      noise let through: the root is certified and the bracket starts at the doubt. A doubt further
//      before it sets IG_EARLIER: the hit is certain, but a tangent root may come before t. A ray that ends
//      with a doubt is a miss flagged IG_UNSURE.
//      A run is where f is within rounding noise of zero: halving further does not help there, so after
//      IG_RUN_DENSE leaves of a run, every IG_RUN_GROWTH more leaves the depth limit drops by one and the
//      leaves grow (the traversal's own order makes the next segments larger), instead of crossing a grazing
//      ray's flat stretch in thousands of leaves.
//      Bisection finds a root of its bracket, not always the first; the first root lies between the bracket's
//      start and the root found. When that stretch is longer than the ray's blur, 2^-IG_BLUR of the working
//      interval plus IG_MERGE times the coordinates' rounding error (about half a pixel at 640 x 480 when the
//      box fills the picture; on a far ray, about as close as float can place a point), the hit is flagged
//      IG_EARLIER: certain, but the first root may lie before t by more than that.
//   5. Everything is bounded: IG_MAX_STEPS shape evaluations per ray; a ray that runs out is flagged.
//   6. The working interval is the clip rounded outward (clip.glsl), a little longer than the ray's part in
//      the box and in [tmin, tmax]. A certified root whose bracket reaches past the part that is certainly
//      inside both (ig_clip_box_inner) may lie in that margin, outside the box, where the exact answer is a
//      miss: such a hit is flagged IG_UNSURE.
//
// What is certified is the ray as given in float (o, d): the shift's rounding is in the coordinates' error.

#ifndef IG_MAX_DEPTH
#define IG_MAX_DEPTH 18
#endif
#ifndef IG_MAX_STEPS
#define IG_MAX_STEPS 1024
#endif
#ifndef IG_RUN_DENSE
#define IG_RUN_DENSE 16
#endif
#ifndef IG_RUN_GROWTH
#define IG_RUN_GROWTH 4
#endif
#ifndef IG_MERGE
#define IG_MERGE 16
#endif
#ifndef IG_BLUR
#define IG_BLUR 10
#endif
#ifndef IG_REFINE_STEPS
#define IG_REFINE_STEPS 30
#endif
#ifndef IG_FAR
#define IG_FAR 1.0e4
#endif

int ig_ray_steps; // shape evaluations the last ray took (set by ig_ray_finish; for statistics)

const int IG_HIT = 1;     // status bit: a root was found (t and the normal are set)
const int IG_UNSURE = 2;  // status bit: float could not decide whether the ray hits (a guess is returned)
const int IG_EARLIER = 4; // status bit: the hit is certain, but a stretch before t was not decided (a tangent
                          // root may come first)

const int IG_START = 0;  // bounding the point s0
const int IG_SEG = 1;    // bounding the segment [a, b]
const int IG_LEAF = 2;   // bounding the point b after an undecided leaf
const int IG_END = 3;    // bounding the point s1 after a run that reaches it
const int IG_REFINE = 4; // bisecting a certified sign change
const int IG_DONE = 5;

struct IgRay {
    vec3 o;       // the shifted origin o + tc d
    vec3 d;
    vec3 e0;      // bound on the shift's rounding, per axis
    float tc;     // t = tc + s
    float s0, s1; // the working interval in s
    int level, index;
    float a, b;   // the current segment in s
    float qs, qh; // the current query: centre and half width in s
    int mode;
    int known;    // certified sign of f at the start of the current run (0: not known)
    int presumed; // known, or where that is 0 the sign of the float value there (for guesses only)
    bool run;     // inside a run of undecided leaves
    float run_a;
    int run_leaves;
    bool guessed; // a float value of the other sign was seen in this run, at s = guess
    float guess;
    bool doubt;   // a run closed without a change of sign: [doubt_a, doubt_b] the last such stretch
    float doubt_a, doubt_b;
    bool far_doubt; // an earlier doubt, not next to the last one
    bool unsure;
    bool earlier;
    float finest; // the width of a leaf at IG_MAX_DEPTH
    int status;
    float s_hit;
    float ra, rb; // refinement bracket: sign known at ra, the other sign at rb
    float bracket_a; // where the bracket started: the first root is in [bracket_a, the root found]
    float bracket_b; // where it ended: a root is certified in [bracket_a, bracket_b]
    float s_after;   // after a hit: a place past the root where f has the other sign (to look for the next root)
    float in0, in1;  // the part of [s0, s1] certainly inside the box and [tmin, tmax] (in0 > in1: none)
    float blur;   // how well float can place a root on this ray (s units)
    int refine_left;
    int steps;
};

float ig_ray_scale(int level)
{
    return intBitsToFloat((127 - level) << 23); // 2^-level, exact
}

float ig_ray_end_of(IgRay ray)
{
    int next = ray.index + 1;
    if (next == (1 << ray.level)) {
        return ray.s1;
    }
    return ray.s0 + (ray.s1 - ray.s0) * (float(next) * ig_ray_scale(ray.level));
}

void ig_ray_ask_point(inout IgRay ray, float s, int mode)
{
    ray.qs = s;
    ray.qh = 0.0;
    ray.mode = mode;
}

void ig_ray_ask_segment(inout IgRay ray)
{
    float m = 0.5 * (ray.a + ray.b);
    float h = max(ray.b - m, m - ray.a);
    ray.qs = m;
    ray.qh = h * (1.0 + IG_UP_REL) + IG_U * (abs(ray.a) + abs(ray.b));
    ray.mode = IG_SEG;
}

void ig_ray_stop(inout IgRay ray, bool hit, float s)
{
    bool unsure = ray.unsure || (!hit && (ray.doubt || ray.far_doubt));
    ray.status = (hit ? IG_HIT : 0) | (unsure ? IG_UNSURE : 0) | (hit && ray.earlier && !unsure ? IG_EARLIER : 0);
    ray.s_hit = s;
    ray.s_after = ray.mode == IG_REFINE ? max(ray.bracket_b, s) : s;
    ray.mode = IG_DONE;
}

// ray.in0, ray.in1: the part of [tmin, tmax] in the box taken exactly, certainly, in s = t - tc. The box is
// clipped from the shifted origin, with its rounding e0 (ig_clip_box_inner), so the margin is of the size of
// the coordinates' own error even for a far origin; tmin and tmax are moved into s with the subtraction's
// rounding counted inward.
void ig_ray_inner(inout IgRay ray, float tmin, float tmax, vec3 lo, vec3 hi)
{
    float i0 = abs(tmin) < ig_inf() ? (tmin - ray.tc) + IG_U * (abs(tmin) + abs(ray.tc)) : tmin;
    float i1 = abs(tmax) < ig_inf() ? (tmax - ray.tc) - IG_U * (abs(tmax) + abs(ray.tc)) : tmax;
    if (!ig_clip_box_inner(ray.o, ray.d, ray.e0, lo, hi, i0, i1)) {
        i0 = 1.0;
        i1 = -1.0;
    }
    ray.in0 = i0;
    ray.in1 = i1;
}

IgRay ig_ray_begin(vec3 o, vec3 d, float tmin, float tmax, vec3 lo, vec3 hi)
{
    IgRay ray;
    ray.d = d;
    ray.steps = 0;
    ray.unsure = false;
    ray.earlier = false;
    ray.doubt = false;
    ray.far_doubt = false;
    ray.run = false;
    ray.run_leaves = 0;
    ray.guessed = false;
    ray.known = 0;
    ray.presumed = 1;
    ray.level = 0;
    ray.index = 0;
    ray.status = 0;
    ray.s_hit = 0.0;
    ray.s_after = 0.0;
    ray.refine_left = IG_REFINE_STEPS;
    float t0 = tmin;
    float t1 = tmax;
    bool inside = ig_clip_box(o, d, lo, hi, t0, t1);
    if (!(t1 < ig_inf())) {
        t1 = t0 + IG_FAR; // no bound at all: a finite working interval (pages clip unbounded shapes first)
    }
    if (!inside || !(t0 <= t1) || !(abs(t0) < ig_inf())) {
        ray.mode = IG_DONE;
        ray.tc = 0.0;
        ray.o = o;
        return ray;
    }
    ray.tc = 0.5 * (t0 + t1);
    ray.o = o + ray.tc * d;
    // o + tc d is rounded twice (the product, the sum): one unit of each
    ray.e0 = (IG_ULP * (abs(ray.tc * d) + abs(ray.o))) * (1.0 + IG_UP_REL) + IG_TINY;
    float pad = IG_U * (abs(t0) + abs(t1) + abs(ray.tc));
    ray.s0 = (t0 - ray.tc) - pad;
    ray.s1 = (t1 - ray.tc) + pad;
    ig_ray_inner(ray, tmin, tmax, lo, hi);
    ray.a = ray.s0;
    ray.b = ray.s1;
    ray.finest = (ray.s1 - ray.s0) * ig_ray_scale(IG_MAX_DEPTH);
    float e = max(max(ray.e0.x, ray.e0.y), ray.e0.z) + IG_ULP * length(ray.o);
    ray.blur = (ray.s1 - ray.s0) * ig_ray_scale(IG_BLUR) + float(IG_MERGE) * e / max(max(abs(d.x), abs(d.y)), abs(d.z));
    ig_ray_ask_point(ray, ray.s0, IG_START);
    return ray;
}

// The three coordinates over the current query, as affine forms with their error.
void ig_ray_query(IgRay ray, out vec3 x, out vec3 y, out vec3 z)
{
    vec3 sd = ray.qs * ray.d;
    vec3 m = ray.o + sd;
    vec3 h = ray.qh * ray.d;
    vec3 e = ray.e0 + IG_ULP * (abs(sd) + abs(m) + abs(h)); // m and h: two roundings and one
    e = e * (1.0 + IG_UP_REL) + IG_TINY;
    x = ig_raa_var(m.x, h.x, e.x);
    y = ig_raa_var(m.y, h.y, e.y);
    z = ig_raa_var(m.z, h.z, e.z);
}

// A certified root in [ra, rb]: bisection from its middle. The origin moves there first (o + m d, its rounding
// added to the coordinates' error), so s stays small and bisection resolves t to float's resolution near the
// root, not to that of the whole working interval (an unbounded shape's is IG_FAR long); everything kept in s
// moves with it, the ends of the bracket outward and the inner part of the box inward by their rounding.
void ig_ray_refine(inout IgRay ray, float ra, float rb)
{
    float m = 0.5 * (ra + rb);
    vec3 md = m * ray.d;
    vec3 o = ray.o + md;
    ray.e0 = (ray.e0 + IG_ULP * (abs(md) + abs(o))) * (1.0 + IG_UP_REL) + IG_TINY;
    ray.o = o;
    ray.tc += m;
    ra = (ra - m) - IG_U * abs(ra - m);
    rb = (rb - m) + IG_U * abs(rb - m);
    ray.in0 = (ray.in0 - m) + IG_U * abs(ray.in0 - m);
    ray.in1 = (ray.in1 - m) - IG_U * abs(ray.in1 - m);
    ray.bracket_a = ra;
    ray.bracket_b = rb;
    ray.ra = ra;
    ray.rb = rb;
    ig_ray_ask_point(ray, 0.5 * (ra + rb), IG_REFINE);
}

// A certified change of sign between the run's start and rb: a root. Its bracket starts at a doubt just
// before (the same stretch of noise); a doubt further before leaves the hit certain but flags IG_EARLIER.
void ig_ray_found(inout IgRay ray, float rb)
{
    float ra = ray.run_a;
    ray.unsure = ray.unsure || ray.known == 0; // the run's starting sign was only presumed
    if (ray.doubt && ray.run_a - ray.doubt_b <= float(IG_MERGE) * ray.finest) {
        ra = ray.doubt_a;
        ray.earlier = ray.earlier || ray.far_doubt;
    } else {
        ray.earlier = ray.earlier || ray.doubt || ray.far_doubt;
    }
    ig_ray_refine(ray, ra, rb);
}

// A run of undecided leaves ended at ray.a: by an excluded segment (sign sg) or by s1 (sign from a point).
void ig_ray_close_run(inout IgRay ray, int sg)
{
    if (sg != 0 && sg != ray.presumed) {
        ig_ray_found(ray, ray.a);
        return;
    }
    if (ray.guessed) { // no certified change of sign, but a float value of the other sign: a guessed hit
        ray.unsure = true;
        ig_ray_stop(ray, true, ray.guess);
        return;
    }
    // no change of sign across it: no root, or two, or noise
    bool next_to_last = ray.doubt && ray.run_a - ray.doubt_b <= float(IG_MERGE) * ray.finest;
    ray.far_doubt = ray.far_doubt || (ray.doubt && !next_to_last);
    ray.doubt_a = next_to_last ? ray.doubt_a : ray.run_a;
    ray.doubt_b = ray.a;
    ray.doubt = true;
    ray.run = false;
}

// Past the current segment: the next one to the right, or the end of the traversal.
void ig_ray_advance(inout IgRay ray)
{
    ray.a = ray.b;
    ray.index += 1;
    for (int i = 0; i <= IG_MAX_DEPTH; ++i) {
        if (ray.level == 0 || (ray.index & 1) != 0) {
            break;
        }
        ray.index >>= 1;
        ray.level -= 1;
    }
    if (ray.level == 0) {
        if (ray.run) {
            ig_ray_ask_point(ray, ray.s1, IG_END);
        } else {
            ig_ray_stop(ray, false, 0.0);
        }
        return;
    }
    ray.b = ig_ray_end_of(ray);
    ig_ray_ask_segment(ray);
}

void ig_ray_note(inout IgRay ray, float value, float s)
{
    // a float value on the other side of zero from the run's starting sign (certified or presumed)
    if (!ray.guessed && float(ray.presumed) * value <= 0.0) {
        ray.guessed = true;
        ray.guess = s;
    }
}

void ig_ray_on_segment(inout IgRay ray, vec3 f)
{
    int sg = ig_raa_sign(f);
    if (sg != 0) {
        if (ray.run) {
            ig_ray_close_run(ray, sg);
            if (ray.mode != IG_SEG) {
                return;
            }
        }
        ray.known = sg;
        ray.presumed = sg;
        ig_ray_advance(ray);
        return;
    }
    bool splittable = ray.b - ray.a > 8.0 * IG_U * max(abs(ray.a), abs(ray.b));
    int grown = max(ray.run_leaves - IG_RUN_DENSE, 0) / IG_RUN_GROWTH;
    int depth = ray.run ? max(IG_MAX_DEPTH - grown, 1) : IG_MAX_DEPTH;
    if (ray.level < depth && splittable) {
        ray.level += 1;
        ray.index *= 2;
        ray.b = ig_ray_end_of(ray);
        ig_ray_ask_segment(ray);
        return;
    }
    if (!ray.run) {
        ray.run = true;
        ray.run_a = ray.a;
        ray.run_leaves = 0;
        ray.guessed = false;
    }
    ray.run_leaves += 1;
    ig_ray_note(ray, f.x, ray.qs);
    ig_ray_ask_point(ray, ray.b, IG_LEAF);
}

void ig_ray_on_leaf_end(inout IgRay ray, vec3 f)
{
    int sb = ig_raa_sign(f);
    ig_ray_note(ray, f.x, ray.b);
    if (sb != 0 && sb != ray.presumed) {
        ig_ray_found(ray, ray.b);
        return;
    }
    ig_ray_advance(ray);
}

void ig_ray_on_refine(inout IgRay ray, vec3 f)
{
    if (float(ray.presumed) * f.x > 0.0) {
        ray.ra = ray.qs;
    } else {
        ray.rb = ray.qs;
    }
    ray.refine_left -= 1;
    float m = 0.5 * (ray.ra + ray.rb);
    bool resolved = ray.rb - ray.ra <= 2.0 * IG_U * max(abs(ray.ra), abs(ray.rb)) || m == ray.ra || m == ray.rb;
    if (ray.refine_left <= 0 || resolved) {
        ray.earlier = ray.earlier || m - ray.bracket_a > ray.blur;
        // NaN-safe: a bracket not shown to be inside is flagged
        ray.unsure = ray.unsure || !(ray.bracket_a >= ray.in0 && ray.bracket_b <= ray.in1);
        ig_ray_stop(ray, true, m);
        return;
    }
    ray.qs = m;
}

void ig_ray_answer(inout IgRay ray, vec3 f)
{
    ray.steps += 1;
    if (ray.mode == IG_START) {
        ray.known = ig_raa_sign(f);
        ray.presumed = f.x < 0.0 ? -1 : 1;
        ray.a = ray.s0;
        ray.b = ray.s1;
        ig_ray_ask_segment(ray);
    } else if (ray.mode == IG_SEG) {
        ig_ray_on_segment(ray, f);
    } else if (ray.mode == IG_LEAF) {
        ig_ray_on_leaf_end(ray, f);
    } else if (ray.mode == IG_END) {
        ig_ray_close_run(ray, ig_raa_sign(f));
        if (ray.mode != IG_REFINE && ray.mode != IG_DONE) {
            ig_ray_stop(ray, false, 0.0);
        }
    } else if (ray.mode == IG_REFINE) {
        ig_ray_on_refine(ray, f);
    }
}

// After the loop: the status bits, and t when IG_HIT is set. A ray that ran out of steps is unsure; it is
// a hit if it was refining a root or had seen a float value of the other sign in its current run.
int ig_ray_finish(IgRay ray, out float t)
{
    t = 0.0;
    ig_ray_steps = ray.steps;
    if (ray.mode != IG_DONE) {
        bool hit = ray.mode == IG_REFINE || (ray.run && ray.guessed);
        float s = ray.mode == IG_REFINE ? 0.5 * (ray.ra + ray.rb) : ray.guess;
        ray.unsure = true;
        ig_ray_stop(ray, hit, s);
    }
    if ((ray.status & IG_HIT) != 0) {
        t = ray.tc + ray.s_hit;
    }
    return ray.status;
}

// The hit point, computed from the shifted origin (more accurate than o + t d for a far origin).
vec3 ig_ray_point(IgRay ray)
{
    return ray.o + ray.s_hit * ray.d;
}

// grad f / |grad f|, or (0, 0, 0) where the gradient vanishes or is not finite (never NaN).
vec3 ig_unit_normal(vec3 g)
{
    float m = max(max(abs(g.x), abs(g.y)), abs(g.z));
    if (!(m > 0.0) || !(m < ig_inf())) {
        return vec3(0.0);
    }
    vec3 s = g / m;
    return s / length(s);
}
