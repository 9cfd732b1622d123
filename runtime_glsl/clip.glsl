// implgen GLSL runtime: clipping a ray to a box or a sphere, in float, rounded outward.
//
// Both return false when the ray misses, and otherwise narrow [t0, t1]. The interval they leave is a little
// larger than the exact one (a few units in the last place of t, IG_CLIP_REL), so a surface that touches its
// box keeps its root; the cost is that a root a hair outside the box can be found too. ig_clip_box_inner gives
// the other side: an interval that lies inside the exact box whatever the rounding, so a root found in the
// margin between the two can be told apart (ray.glsl flags it: its hit or miss is not decided).
// A box bound at or beyond IG_OPEN (1e30) is an open side: shapes without bounds on an axis use it.

const float IG_OPEN = 1.0e30;
const float IG_CLIP_REL = 1.9073486328125e-6; // 2^-19
const float IG_CLIP_IN_REL = 4.76837158203125e-7; // 2^-21: 8 units, over a slab t's 4.5 (a subtraction,
                                                  // 1 / d within 2.5 units in GLSL ES, a product)

float ig_widen_down(float t)
{
    return t - IG_CLIP_REL * abs(t);
}

float ig_widen_up(float t)
{
    return t + IG_CLIP_REL * abs(t);
}

// One axis of the slab test; an open or parallel side keeps [t0, t1] when the origin is inside it.
bool ig_clip_slab(float o, float d, float lo, float hi, inout float t0, inout float t1)
{
    if (d == 0.0) {
        return !(o < lo || o > hi); // NaN bounds never clip
    }
    float inv = 1.0 / d;
    float ta = lo <= -IG_OPEN ? -ig_inf() * sign(d) : (lo - o) * inv;
    float tb = hi >= IG_OPEN ? ig_inf() * sign(d) : (hi - o) * inv;
    float tn = ig_widen_down(min(ta, tb));
    float tf = ig_widen_up(max(ta, tb));
    t0 = max(t0, tn);
    t1 = min(t1, tf);
    return t0 <= t1;
}

bool ig_clip_box(vec3 o, vec3 d, vec3 lo, vec3 hi, inout float t0, inout float t1)
{
    return ig_clip_slab(o.x, d.x, lo.x, hi.x, t0, t1) && ig_clip_slab(o.y, d.y, lo.y, hi.y, t0, t1)
        && ig_clip_slab(o.z, d.z, lo.z, hi.z, t0, t1);
}

float ig_narrow_up(float t)
{
    return abs(t) < ig_inf() ? t + IG_CLIP_IN_REL * abs(t) : t;
}

float ig_narrow_down(float t)
{
    return abs(t) < ig_inf() ? t - IG_CLIP_IN_REL * abs(t) : t;
}

// One axis of ig_clip_box_inner: the bounds moved inward by 8 units of their own (a bound computed from
// params carries a few roundings; the sum's own rounding is within them) and by the origin's error e, the
// slab's t narrowed by IG_CLIP_IN_REL (the quotient's roundings).
bool ig_clip_slab_inner(float o, float d, float e, float lo, float hi, inout float t0, inout float t1)
{
    float lo_in = lo + (8.0 * IG_ULP * abs(lo) + e);
    float hi_in = hi - (8.0 * IG_ULP * abs(hi) + e);
    if (d == 0.0) {
        return (lo <= -IG_OPEN || o > lo_in) && (hi >= IG_OPEN || o < hi_in);
    }
    float inv = 1.0 / d;
    float ta = lo <= -IG_OPEN ? -ig_inf() * sign(d) : (lo_in - o) * inv;
    float tb = hi >= IG_OPEN ? ig_inf() * sign(d) : (hi_in - o) * inv;
    t0 = max(t0, ig_narrow_up(min(ta, tb)));
    t1 = min(t1, ig_narrow_down(max(ta, tb)));
    return t0 <= t1;
}

// [t0, t1] narrowed to a part of the ray o + t d that is inside the box [lo, hi] taken exactly, for every origin
// within e of o (per axis); false when no part is certainly inside (the ray misses the box, or only grazes
// its margin).
bool ig_clip_box_inner(vec3 o, vec3 d, vec3 e, vec3 lo, vec3 hi, inout float t0, inout float t1)
{
    return ig_clip_slab_inner(o.x, d.x, e.x, lo.x, hi.x, t0, t1)
        && ig_clip_slab_inner(o.y, d.y, e.y, lo.y, hi.y, t0, t1)
        && ig_clip_slab_inner(o.z, d.z, e.z, lo.z, hi.z, t0, t1);
}

// The sphere |p - c| <= radius. The chord is found from the ray's closest approach to c (the vector q), not
// from b^2 - 4ac, which cancels for a far origin.
bool ig_clip_sphere(vec3 o, vec3 d, vec3 c, float radius, inout float t0, inout float t1)
{
    float dd = dot(d, d);
    if (!(dd > 0.0)) {
        return false;
    }
    vec3 oc = o - c;
    float tm = -dot(oc, d) / dd; // closest approach
    vec3 q = oc + tm * d;
    float h2 = radius * radius - dot(q, q);
    if (h2 < 0.0) {
        return false;
    }
    float half_chord = sqrt(h2 / dd);
    float pad = IG_CLIP_REL * (abs(tm) + half_chord) + 1.0e-4 * radius / sqrt(dd);
    t0 = max(t0, tm - half_chord - pad);
    t1 = min(t1, tm + half_chord + pad);
    return t0 <= t1;
}
