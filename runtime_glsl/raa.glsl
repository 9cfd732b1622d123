// implgen GLSL runtime: reduced affine arithmetic (RAA) in float, conservative under rounding.
//
// Along one segment of a ray every coordinate is an affine function of one variable e in [-1, 1]:
// x(e) = m + h*e. An affine form vec3(c, l, r) stands for every function v(e) with |v(e) - (c + l*e)| <= r
// on [-1, 1]: a centre, the slope in e, and a radius that collects everything else (the e^2 terms of
// products, the inputs' own error, and rounding). Because the ray is one-dimensional, one noise symbol is
// exact for the inputs, and products keep the linear part instead of losing it as interval arithmetic does
// (after Knoll et al. 2009, "Fast ray tracing of arbitrary implicit surfaces with interval and affine
// arithmetic": reduced affine arithmetic for shaders).
//
// GLSL has no directed rounding: + - * are correctly rounded, but in a rounding mode that is not defined (an
// error up to one unit in the last place, 2^-23 relative), and a compiler may fuse a*b + c. Every operation
// therefore adds to r a bound on the rounding of the centre and the slope, IG_U (2^-22: one unit for each of
// the two roundings in the longest expression below) times the sum of the magnitudes it combined, and the
// radius's own sum is rounded up by IG_UP_REL (2^-20, for its dozen roundings). IG_TINY (2^-100) covers products that underflow (GPUs may flush denormals to zero). An infinity
// or a NaN anywhere makes every test below false: the segment is then simply "not decided".
//
// No #version line: the page or the test prepends `#version 300 es` + precision, or `#version 450`.

const float IG_ULP = 1.1920928955078125e-7;     // 2^-23: one unit in the last place, relative
const float IG_U = 2.384185791015625e-7;        // 2^-22: rounding allowance of one operation, relative
const float IG_UP_REL = 9.5367431640625e-7;     // 2^-20: how much a radius is rounded up
const float IG_TINY = 7.888609052210118e-31;    // 2^-100: absolute floor (underflow, flushed denormals)
const float IG_PARAM_REL = 1.1920928955078125e-7; // 2^-23: a param uploaded as float from a double

float ig_up(float r)
{
    return r * (1.0 + IG_UP_REL) + IG_TINY;
}

// a coordinate: centre m, slope h (half the segment times the direction), error e
vec3 ig_raa_var(float m, float h, float e)
{
    return vec3(m, h, e);
}

// a constant: the float nearest to it and a bound on the difference (printed by the generator)
vec3 ig_raa_const(float c, float e)
{
    return vec3(c, 0.0, e);
}

// a param: the float the page uploaded, which is within 2^-24 of the double it was given
vec3 ig_raa_param(float p)
{
    return vec3(p, 0.0, abs(p) * IG_PARAM_REL + IG_TINY);
}

vec3 ig_raa_neg(vec3 a)
{
    return vec3(-a.x, -a.y, a.z);
}

vec3 ig_raa_add(vec3 a, vec3 b)
{
    float e = IG_U * (abs(a.x) + abs(b.x) + abs(a.y) + abs(b.y));
    return vec3(a.x + b.x, a.y + b.y, ig_up(a.z + b.z + e));
}

vec3 ig_raa_sub(vec3 a, vec3 b)
{
    return ig_raa_add(a, ig_raa_neg(b));
}

// (ca + la e + da)(cb + lb e + db) = ca cb + (ca lb + la cb) e + la lb e^2 + da*(b's affine part) + db*(a's) + da db;
// e^2 in [0, 1] is 1/2 +- 1/2.
vec3 ig_raa_mul(vec3 a, vec3 b)
{
    float cc = a.x * b.x;
    float ll = a.y * b.y;
    float cl = a.x * b.y;
    float lc = a.y * b.x;
    float ma = abs(a.x) + abs(a.y);
    float mb = abs(b.x) + abs(b.y);
    float r = 0.5 * abs(ll) + a.z * mb + b.z * ma + a.z * b.z + IG_U * (abs(cc) + abs(ll) + abs(cl) + abs(lc));
    return vec3(cc + 0.5 * ll, cl + lc, ig_up(r));
}

vec3 ig_raa_sqr(vec3 a)
{
    float cc = a.x * a.x;
    float ll = a.y * a.y;
    float cl = a.x * a.y;
    float ma = abs(a.x) + abs(a.y);
    float r = 0.5 * ll + a.z * (2.0 * ma + a.z) + IG_U * (cc + ll + 2.0 * abs(cl));
    return vec3(cc + 0.5 * ll, 2.0 * cl, ig_up(r));
}

// Does the form exclude zero on the whole segment? (false for NaN and infinity)
bool ig_raa_nonzero(vec3 f)
{
    return abs(f.x) > (abs(f.y) + f.z) * (1.0 + IG_UP_REL);
}

// The certified sign of the form on its segment: +1, -1, or 0 when zero is not excluded.
int ig_raa_sign(vec3 f)
{
    return ig_raa_nonzero(f) ? (f.x > 0.0 ? 1 : -1) : 0;
}

float ig_inf()
{
    return uintBitsToFloat(0x7F800000u);
}
