// implgen GLSL runtime: the pinhole camera, as runtime_c/tracer_render.c builds it.
//
// fov is the vertical field of view in degrees; pixel is in image coordinates (x to the right, y down, the
// pixel's centre at +0.5), which is gl_FragCoord with y flipped: vec2(gl_FragCoord.x, size.y - gl_FragCoord.y).
// The direction is not normalised (the runtime does not need unit directions), exactly as in C.

struct IgCamera {
    vec3 eye;
    vec3 u, v, w; // right, up, backwards
    float tan_half;
    float aspect;
};

IgCamera ig_camera(vec3 eye, vec3 look_at, vec3 up, float fov_degrees, vec2 size)
{
    IgCamera cam;
    cam.eye = eye;
    cam.w = normalize(eye - look_at);
    vec3 u = cross(up, cam.w);
    if (!(dot(u, u) > 0.0)) { // up parallel to the view direction: any perpendicular, as in C
        u = cross(abs(cam.w.x) > 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0), cam.w);
    }
    cam.u = normalize(u);
    cam.v = cross(cam.w, cam.u);
    cam.tan_half = tan(0.5 * fov_degrees * 3.14159265358979 / 180.0);
    cam.aspect = size.x / size.y;
    return cam;
}

vec3 ig_camera_dir(IgCamera cam, vec2 pixel, vec2 size)
{
    float px = (2.0 * pixel.x / size.x - 1.0) * cam.tan_half * cam.aspect;
    float py = (1.0 - 2.0 * pixel.y / size.y) * cam.tan_half;
    return px * cam.u + py * cam.v - cam.w;
}
