// implgen GLSL runtime: shading one hit, two-sided, and marking the pixels float could not decide.
//
// n is the unit outward normal (grad f / |grad f|, or zero at a singular point), d the ray direction. The
// side the ray sees is the front when n faces the ray, else the back (the inside of the shape: f < 0), and
// the two sides have their own colours, as the C tracer's two-sided materials. One directional light,
// Lambert plus a Blinn-Phong highlight; a zero normal is shaded with ambient light only.

struct IgMaterial {
    vec3 front;
    vec3 back;
    float ambient;
    float diffuse;
    float specular;
    float shininess;
};

IgMaterial ig_material_default()
{
    return IgMaterial(vec3(0.85, 0.45, 0.3), vec3(0.3, 0.55, 0.85), 0.15, 0.75, 0.35, 40.0);
}

vec3 ig_shade(IgMaterial m, vec3 n, vec3 d, vec3 to_light)
{
    vec3 u = normalize(d);
    bool back = !(dot(n, u) < 0.0);
    vec3 nf = back ? -n : n;
    vec3 base = back ? m.back : m.front;
    vec3 colour = m.ambient * base;
    vec3 l = normalize(to_light);
    float ndl = dot(nf, l);
    if (ndl > 0.0) {
        vec3 hv = normalize(l - u);
        float ndh = max(dot(nf, hv), 0.0);
        colour += m.diffuse * ndl * base + m.specular * pow(ndh, m.shininess);
    }
    return colour;
}

// A pixel the runtime flagged IG_UNSURE: a checker of the shaded colour and magenta, so it is seen.
vec3 ig_mark_unsure(vec3 colour, vec2 pixel)
{
    bool odd = (int(pixel.x) + int(pixel.y)) % 2 == 1;
    return odd ? vec3(1.0, 0.0, 1.0) : colour;
}
