// implgen share: the surface renderer. One object, IgSurface, with no page in it, so any page can draw a
// generated shape with it: the shared page (implgen share) and the viewer's GPU preview (view/static/gpu.js).
//
//   const r = new IgSurface.Renderer(canvas);              // WebGL2; throws an Error saying why if there is none
//   r.setEquationProgram({name, shape, runtime, header, params})   // '' or the compiler's log
//   r.setParams([1.0, 0.25]);  r.setCamera({eye, target, up, fov});  r.setClip({kind: "sphere", size: 2});
//   r.setColours({outside, inside, background});  r.setMarkUnsure(true);  r.setSize(640, 480);
//   r.setLights([{position, colour}]);  r.setShadows(true);  r.setMaterial({ambient, diffuse, specular, shininess});
//   r.draw({scale: 1, rows: [y0, y1]});                     // draw now (all of it, or a band); milliseconds
//   const p = new IgSurface.Progressive(r, {onIdle});      // redraw on change only, coarse first, in bands
//   p.invalidate(moving);
//
// docs/share.md describes the API and the picture it draws; docs/glsl.md the shader it is built from. Plain
// JavaScript, no build step, nothing fetched: the shape's and the runtime's GLSL come in as strings.
"use strict";

const IgSurface = (() => {
  // The prefix of the shape's GLSL identifiers (implgen.codegen.backends.glsl.printer.glsl_name: its name, or its name spelled for
  // GLSL): runs of letters and digits joined by single underscores, not gl_ or webgl_ first.
  const NAME = /^(?!gl_|webgl_)[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9]+)*$/i;
  const SHAPE_FUNCTIONS = ["value", "gradient", "normal", "bounds", "raa", "hit"]; // glslprogram.SHAPE_FUNCTIONS
  const VERTEX = "#version 300 es\nin vec2 p;\nvoid main() { gl_Position = vec4(p, 0.0, 1.0); }\n";
  const CLIPS = Object.freeze(Object.assign(Object.create(null), { none: 0, sphere: 1, box: 2 })); // no prototype
  const MAX_LIGHTS = 4;
  const LIGHT = [-0.6, 0.8, 1.0]; // the default key light: towards it, in the camera's right, up and back

  // The page's main: camera ray, clip, the surface cut open by the clip (SURFER's picture: both sides show) or
  // the shape's solid cut by the clip (its cut face in the inside colour), two-sided shading under up to
  // MAX_LIGHTS lights (point lights in the world, or directions in the camera's frame), shadows if asked, the
  // flagged pixels marked. ig_page_output 1 writes the status instead (red: hit, green: IG_UNSURE). It is the
  // same text for every shape: it calls the shape's functions as IG_SHAPE_BOUNDS, IG_SHAPE_RAA, IG_SHAPE_HIT and
  // sizes its lights by IG_PAGE_MAX_LIGHTS, #defines that fragmentSource writes before the runtime.
  const MAIN = `
uniform vec2 ig_page_size;
uniform vec3 ig_page_eye;
uniform vec3 ig_page_look;
uniform vec3 ig_page_up;
uniform float ig_page_fov;
uniform int ig_page_clip;        // 0 none, 1 sphere of radius ig_page_clip_size, 2 box [-size, size]^3
uniform float ig_page_clip_size;
uniform int ig_page_cut;         // 1: the solid cut by the clip, its cut face painted; 0: the surface cut open
uniform vec3 ig_page_outside;
uniform vec3 ig_page_inside;
uniform vec3 ig_page_background;
uniform vec4 ig_page_material;   // ambient, diffuse, specular, shininess
uniform int ig_page_nlights;
uniform vec4 ig_page_light[IG_PAGE_MAX_LIGHTS];      // w = 1: a point in the world; w = 0: towards it, camera frame
uniform vec3 ig_page_light_colour[IG_PAGE_MAX_LIGHTS];
uniform int ig_page_shadows;     // 1: a shadow ray to each light
uniform int ig_page_mark;        // 1: pixels flagged IG_UNSURE get the magenta checker
uniform int ig_page_output;      // 0: the colour; 1: the status (red: hit, green: not sure)
out vec4 ig_page_colour;

// One loop per pixel (ig_page_run) asks the shape everything the pixel needs, one question after the other:
// the sign of f where the camera ray enters the cut clip, the camera ray, the places a shadow ray may start
// from, each light's cut and shadow ray. Its inner loop evaluates f over a point or over the current ray's
// segments and points (ray.glsl) in its one call of IG_SHAPE_RAA, and the camera's hit gets its normal from
// the one call of IG_SHAPE_NORMAL: the shape's tree is in the program once, as in a program that calls
// IG_SHAPE_HIT once (the GLSL test harness's). A compiler inlines every call: with a call of IG_SHAPE_HIT for
// the camera and one for the shadows, and f at points in three more places, the page held the tree eight
// times. That was the difference found between the two programs when a large tree (a Chebyshev form of
// degree 16 to 24) drew 9-13 times slower in the page than in the harness on a GPU (docs/share.md).

const int IG_PAGE_DONE = 0;
const int IG_PAGE_CAMERA_SIDE = 1; // f's sign where the camera ray enters the cut clip
const int IG_PAGE_CAMERA = 2;      // the camera ray
const int IG_PAGE_START = 3;       // f's sign where the shadow rays would start
const int IG_PAGE_SHADOW_SIDE = 4; // f's sign where a shadow ray enters the cut clip
const int IG_PAGE_SHADOW = 5;      // a shadow ray
// the questions a pixel asks at most: two for the camera (the cut, the ray), three places for shadow rays to
// start from, two for each light (the cut, the shadow ray)
const int IG_PAGE_JOBS = 5 + 2 * IG_PAGE_MAX_LIGHTS;

IgCamera ig_page_cam;
vec3 ig_page_dir;      // the camera ray's direction
int ig_page_phase;
int ig_page_status;    // the pixel's status bits
vec3 ig_page_rgb;
IgRay ig_page_ray;     // the ray being traced: from ig_page_ro along ig_page_rd over [ig_page_t0, ig_page_t1]
vec3 ig_page_ro;
vec3 ig_page_rd;
float ig_page_t0;
float ig_page_t1;
vec3 ig_page_q;        // the point asked about, and its coordinates' error
vec3 ig_page_qe;
int ig_page_camera_unsure; // IG_UNSURE when the camera ray's side at the clip was a guess
// shading the camera's hit
vec3 ig_page_base;
vec3 ig_page_p;
vec3 ig_page_nf;
vec3 ig_page_u;
float ig_page_off;
vec3 ig_page_start;    // where shadow rays leave
int ig_page_tries;
int ig_page_light_i;   // the light whose shadow ray is traced

// The sign of f at the point o + t0 d where a ray enters the clip is asked next (phase); outside the shape's
// box the solid is not there (a leaf is its solid cut by its box), and no question is needed: false.
bool ig_page_ask_side(vec3 o, vec3 d, float t0, int phase)
{
    vec3 p = o + t0 * d;
    vec3 lo, hi;
    IG_SHAPE_BOUNDS(lo, hi);
    if (any(lessThan(p, lo)) || any(greaterThan(p, hi))) {
        return false;
    }
    ig_page_q = p;
    ig_page_qe = (IG_ULP * (abs(t0 * d) + abs(p))) * (1.0 + IG_UP_REL) + IG_TINY;
    ig_page_phase = phase;
    return true;
}

void ig_page_ask_start()
{
    ig_page_q = ig_page_start;
    ig_page_qe = IG_ULP * abs(ig_page_start) * (1.0 + IG_UP_REL) + IG_TINY;
    ig_page_phase = IG_PAGE_START;
}

void ig_page_trace(vec3 o, vec3 d, float t0, float t1, int phase)
{
    ig_page_ro = o;
    ig_page_rd = d;
    ig_page_t0 = t0;
    ig_page_t1 = t1;
    ig_page_phase = phase;
}

vec3 ig_page_clip_normal(vec3 p)
{
    if (ig_page_clip == 1) {
        return normalize(p);
    }
    vec3 a = abs(p);
    vec3 axis = a.x >= a.y && a.x >= a.z ? vec3(1.0, 0.0, 0.0) : (a.y >= a.z ? vec3(0.0, 1.0, 0.0) : vec3(0.0, 0.0, 1.0));
    return axis * sign(p);
}

bool ig_page_clip_ray(vec3 o, vec3 d, inout float t0, inout float t1)
{
    if (ig_page_clip == 1) {
        return ig_clip_sphere(o, d, vec3(0.0), ig_page_clip_size, t0, t1);
    } else if (ig_page_clip == 2) {
        return ig_clip_box(o, d, vec3(-ig_page_clip_size), vec3(ig_page_clip_size), t0, t1);
    }
    return t0 <= t1;
}

// Towards light i from the hit point: its direction (unnormalised), or length 0 when it does not light the side
// seen.
vec3 ig_page_towards(int i)
{
    vec4 lp = ig_page_light[i];
    vec3 l = lp.w > 0.5 ? lp.xyz - ig_page_p : lp.x * ig_page_cam.u + lp.y * ig_page_cam.v + lp.z * ig_page_cam.w;
    float ll = length(l);
    return ll > 0.0 && dot(ig_page_nf, l) / ll > 0.0 ? l : vec3(0.0);
}

// Two-sided shading as the C tracer's (runtime_c/tracer_shade.c): light i's Lambert and Blinn-Phong terms times
// its colour, added when nothing blocks it.
void ig_page_add_light(int i)
{
    vec3 l = ig_page_towards(i);
    float ll = length(l);
    float ndl = dot(ig_page_nf, l) / ll;
    vec3 hv = normalize(l / ll - ig_page_u);
    float ndh = dot(ig_page_nf, hv);
    float spec = ndh > 0.0 ? ig_page_material.z * pow(ndh, ig_page_material.w) : 0.0;
    ig_page_rgb += ig_page_light_colour[i] * (ig_page_material.y * ig_page_base * ndl + spec);
}

// The lights from ig_page_light_i on: each that lights the side seen is added, or (shadows) its shadow ray is
// asked for -- what the picture shows blocks it: the surface inside the clip, or (cut solid) the solid where
// the ray enters the clip.
void ig_page_next_light()
{
    for (int i = 0; i < IG_PAGE_MAX_LIGHTS; ++i) {
        int k = ig_page_light_i;
        if (k >= ig_page_nlights) {
            break;
        }
        vec3 l = ig_page_towards(k);
        if (!(length(l) > 0.0)) {
            ig_page_light_i += 1;
            continue;
        }
        if (ig_page_shadows == 0) {
            ig_page_add_light(k);
            ig_page_light_i += 1;
            continue;
        }
        bool point = ig_page_light[k].w > 0.5;
        vec3 towards = point ? ig_page_light[k].xyz - ig_page_start : l;
        float t0 = 0.0;
        float t1 = point ? 1.0 : ig_inf();
        if (!ig_page_clip_ray(ig_page_start, towards, t0, t1)) {
            ig_page_add_light(k);
            ig_page_light_i += 1;
            continue;
        }
        ig_page_ro = ig_page_start;
        ig_page_rd = towards;
        ig_page_t0 = t0;
        ig_page_t1 = t1;
        bool cut = ig_page_cut == 1 && ig_page_clip != 0 && t0 > 0.0;
        if (!(cut && ig_page_ask_side(ig_page_start, towards, t0, IG_PAGE_SHADOW_SIDE))) {
            ig_page_trace(ig_page_start, towards, t0, t1, IG_PAGE_SHADOW);
        }
        return;
    }
    ig_page_phase = IG_PAGE_DONE;
}

// The camera's hit (or the cut face) at p with normal n: ambient, then the lights. Shadow rays leave a little
// off the surface (the float hit point is only that accurate), and further, up to 64 times, until f's sign is
// certain there (a high degree's rounding noise is wide).
void ig_page_shade(vec3 front, vec3 back, vec3 n, vec3 p)
{
    ig_page_u = normalize(ig_page_dir);
    bool behind = !(dot(n, ig_page_u) < 0.0);
    ig_page_nf = behind ? -n : n;
    ig_page_base = behind ? back : front;
    ig_page_rgb = ig_page_material.x * ig_page_base;
    ig_page_p = p;
    ig_page_off = 4.0e-4 * (length(p) + length(p - ig_page_cam.eye)) + 1.0e-6;
    ig_page_start = p + ig_page_nf * ig_page_off;
    ig_page_light_i = 0;
    ig_page_tries = 0;
    if (ig_page_shadows != 0) {
        ig_page_ask_start();
    } else {
        ig_page_next_light();
    }
}

// f's sign at the point asked about: its answer.
void ig_page_on_point(int sg, float guess)
{
    bool solid = sg < 0 || (sg == 0 && guess < 0.0); // where the ray enters the cut clip
    int unsure = sg == 0 ? IG_UNSURE : 0;
    if (ig_page_phase == IG_PAGE_CAMERA_SIDE) {
        if (solid) { // the cut face: the solid's inside, flat on the clip
            ig_page_status = IG_HIT | unsure;
            vec3 p = ig_page_cam.eye + ig_page_t0 * ig_page_dir;
            ig_page_shade(ig_page_inside, ig_page_inside, ig_page_clip_normal(p), p);
        } else {
            ig_page_camera_unsure = unsure;
            ig_page_trace(ig_page_ro, ig_page_rd, ig_page_t0, ig_page_t1, IG_PAGE_CAMERA);
        }
    } else if (ig_page_phase == IG_PAGE_START) {
        ig_page_tries += 1;
        if (sg == 0 && ig_page_tries < 3) {
            ig_page_off *= 4.0;
            ig_page_start = ig_page_p + ig_page_nf * ig_page_off;
            ig_page_ask_start();
            return;
        }
        if (sg == 0) { // the fourth place is taken unasked
            ig_page_start = ig_page_p + ig_page_nf * (4.0 * ig_page_off);
        }
        ig_page_next_light();
    } else if (ig_page_phase == IG_PAGE_SHADOW_SIDE) {
        if (solid) {
            ig_page_status |= unsure;
            ig_page_light_i += 1;
            ig_page_next_light();
        } else {
            ig_page_trace(ig_page_ro, ig_page_rd, ig_page_t0, ig_page_t1, IG_PAGE_SHADOW);
        }
    }
}

// The traced ray is finished: the camera's hit shaded, or a light blocked or added.
void ig_page_on_ray()
{
    float t;
    int s = ig_ray_finish(ig_page_ray, t);
    if (ig_page_phase == IG_PAGE_CAMERA) {
        ig_page_status = s | ig_page_camera_unsure;
        if ((s & IG_HIT) == 0) {
            ig_page_phase = IG_PAGE_DONE;
            return;
        }
        vec3 n = IG_SHAPE_NORMAL(ig_ray_point(ig_page_ray));
        ig_page_shade(ig_page_outside, ig_page_inside, n, ig_page_cam.eye + t * ig_page_dir);
        return;
    }
    ig_page_status |= s & IG_UNSURE;
    if ((s & IG_HIT) == 0) {
        ig_page_add_light(ig_page_light_i);
    }
    ig_page_light_i += 1;
    ig_page_next_light();
}

// Everything the pixel asks of the shape, one question (a ray, or a point) after the other; the inner loop is
// the one that evaluates the shape, as a shape's own IG_SHAPE_HIT does.
void ig_page_run()
{
    for (int job = 0; job < IG_PAGE_JOBS && ig_page_phase != IG_PAGE_DONE; ++job) {
        bool ray = ig_page_phase == IG_PAGE_CAMERA || ig_page_phase == IG_PAGE_SHADOW;
        if (ray) {
            vec3 lo, hi;
            IG_SHAPE_BOUNDS(lo, hi);
            ig_page_ray = ig_ray_begin(ig_page_ro, ig_page_rd, ig_page_t0, ig_page_t1, lo, hi);
        }
        vec3 f = vec3(0.0);
        for (int i = 0; i < IG_MAX_STEPS && !(ray && ig_page_ray.mode == IG_DONE); ++i) {
            vec3 x, y, z;
            if (ray) {
                ig_ray_query(ig_page_ray, x, y, z);
            } else {
                x = ig_raa_var(ig_page_q.x, 0.0, ig_page_qe.x);
                y = ig_raa_var(ig_page_q.y, 0.0, ig_page_qe.y);
                z = ig_raa_var(ig_page_q.z, 0.0, ig_page_qe.z);
            }
            f = IG_SHAPE_RAA(x, y, z);
            if (!ray) {
                break;
            }
            ig_ray_answer(ig_page_ray, f);
        }
        if (ray) {
            ig_page_on_ray();
        } else {
            ig_page_on_point(ig_raa_sign(f), f.x);
        }
    }
    if (ig_page_phase != IG_PAGE_DONE) {
        ig_page_status |= IG_UNSURE; // out of questions (not reached: IG_PAGE_JOBS counts them all)
    }
}

void main()
{
    vec2 pixel = vec2(gl_FragCoord.x, ig_page_size.y - gl_FragCoord.y);
    ig_page_cam = ig_camera(ig_page_eye, ig_page_look, ig_page_up, ig_page_fov, ig_page_size);
    ig_page_dir = ig_camera_dir(ig_page_cam, pixel, ig_page_size);
    float t0 = 0.0;
    float t1 = ig_inf();
    ig_page_status = 0;
    ig_page_camera_unsure = 0;
    ig_page_rgb = ig_page_background;
    ig_page_phase = IG_PAGE_DONE;
    if (ig_page_clip_ray(ig_page_cam.eye, ig_page_dir, t0, t1)) {
        ig_page_ro = ig_page_cam.eye;
        ig_page_rd = ig_page_dir;
        ig_page_t0 = t0;
        ig_page_t1 = t1;
        bool cut = ig_page_cut == 1 && ig_page_clip != 0 && t0 > 0.0;
        if (!(cut && ig_page_ask_side(ig_page_cam.eye, ig_page_dir, t0, IG_PAGE_CAMERA_SIDE))) {
            ig_page_trace(ig_page_cam.eye, ig_page_dir, t0, t1, IG_PAGE_CAMERA);
        }
    }
    ig_page_run();
    int status = ig_page_status;
    vec3 rgb = ig_page_rgb;
    if (ig_page_output == 1) {
        ig_page_colour = vec4((status & IG_HIT) != 0 ? 1.0 : 0.0, (status & IG_UNSURE) != 0 ? 1.0 : 0.0, 0.0, 1.0);
        return;
    }
    if (ig_page_mark != 0 && (status & IG_UNSURE) != 0) {
        rgb = ig_mark_unsure(rgb, pixel);
    }
    ig_page_colour = vec4(clamp(rgb, 0.0, 1.0), 1.0);
}
`;

  /** The fragment shader for a shape: header, runtime, shape, main (docs/glsl.md, "A program"). The header (the
   * #version and precision lines) comes from the server or the page's data, as the runtime does: its one
   * source is implgen.codegen.backends.glsl.program.HEADERS["es"]. */
  function fragmentSource(name, shape, runtime, header) {
    if (typeof name !== "string" || name.length > 256 || !NAME.test(name)) {
      throw new Error(`not the prefix of a shape's GLSL identifiers: ${JSON.stringify(String(name)).slice(0, 80)}`);
    }
    if (typeof header !== "string" || !header.startsWith("#version 300 es\n")) throw new Error("no GLSL ES 3.00 header");
    const defines = [`#define IG_PAGE_MAX_LIGHTS ${MAX_LIGHTS | 0}\n`];
    for (const f of SHAPE_FUNCTIONS) defines.push(`#define IG_SHAPE_${f.toUpperCase()} ${name}_${f}\n`);
    return header + defines.join("") + runtime + "\n" + shape + "\n" + MAIN;
  }

  /** VERTEX and a fragment shader compiled and linked, the vertex attribute `p` at location 0: the program, or
   * an Error carrying the compiler's (or the linker's) log. Also the GLSL test harness's (implgen.bench.webgl). */
  function compileProgram(gl, fragment) {
    const shaders = [];
    const compile = (type, text) => {
      const s = gl.createShader(type);
      gl.shaderSource(s, text);
      gl.compileShader(s);
      shaders.push(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s) || "the shader did not compile");
      return s;
    };
    const prog = gl.createProgram();
    try {
      gl.attachShader(prog, compile(gl.VERTEX_SHADER, VERTEX));
      gl.attachShader(prog, compile(gl.FRAGMENT_SHADER, fragment));
      gl.bindAttribLocation(prog, 0, "p");
      gl.linkProgram(prog);
      if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(prog) || "the program did not link");
    } catch (err) {
      gl.deleteProgram(prog);
      throw err;
    } finally {
      for (const s of shaders) gl.deleteShader(s); // the program keeps what it linked
    }
    return prog;
  }

  /** The one triangle that covers the viewport, bound to attribute 0; returns its buffer. */
  function fullScreenTriangle(gl) {
    const vbo = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, vbo);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
    return vbo;
  }

  const finite3 = (v, what) => {
    if (!Array.isArray(v) || v.length !== 3 || !v.every(Number.isFinite)) throw new Error(`${what}: three numbers`);
    return v.map(Number);
  };

  class Renderer {
    constructor(canvas) {
      this.canvas = canvas;
      // preserveDrawingBuffer: a frame drawn in bands over several animation frames stays on the canvas
      const gl = canvas.getContext("webgl2", { antialias: false, preserveDrawingBuffer: true, alpha: false });
      if (!gl) throw new Error("this browser has no WebGL2");
      this.gl = gl;
      this.prog = null;
      this.name = "";
      this.fragment = "";
      this.nparams = 0;
      this.params = [];
      this.camera = { eye: [3, 2, 4], target: [0, 0, 0], up: [0, 1, 0], fov: 40 };
      this.clip = { kind: "none", size: 1, cut: false };
      this.material = null; // the page's (share/page.py MATERIAL, in its data): set before the first draw
      this.lights = [{ direction: LIGHT, colour: [1, 1, 1] }];
      this.shadows = false;
      this.colours = { outside: [0.95, 0.75, 0.3], inside: [0.35, 0.55, 0.95], background: [0.12, 0.12, 0.14] };
      this.markUnsure = true;
      this.width = canvas.width;
      this.height = canvas.height;
      this.coarse = null; // {fbo, rb, w, h}: the target of scaled-down draws
      fullScreenTriangle(gl);
    }

    /** Which WebGL2 this is: [version, renderer]. */
    info() {
      const gl = this.gl;
      const e = gl.getExtension("WEBGL_debug_renderer_info");
      return [gl.getParameter(gl.VERSION), e ? gl.getParameter(e.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER)];
    }

    /** A new shape: `name` (an identifier), `shape` (its generated GLSL), `runtime` (runtime_glsl/, concatenated),
     * `params` (how many it takes). Returns '' or the compiler's log; on failure the old program stays. */
    setEquationProgram({ name, shape, runtime, header, params }) {
      const gl = this.gl;
      let src;
      try {
        src = fragmentSource(name, shape, runtime, header);
      } catch (err) {
        return String(err.message || err);
      }
      try {
        const prog = compileProgram(gl, src);
        if (this.prog) gl.deleteProgram(this.prog);
        this.prog = prog;
      } catch (err) {
        return String(err.message || err);
      }
      this.name = name;
      this.fragment = src; // the fragment shader it compiled (for tests and for people poking at the page)
      this.nparams = params | 0;
      this.params = new Array(this.nparams).fill(0);
      this.uniforms = {};
      return "";
    }

    /** The params' values, in the order the spec declares them. */
    setParams(values) {
      const v = Array.from(values, Number);
      if (v.length !== this.nparams || !v.every(Number.isFinite)) {
        throw new Error(`setParams: ${this.nparams} finite numbers`);
      }
      this.params = v;
    }

    /** Pinhole camera: eye, target, up (world), vertical field of view in degrees. */
    setCamera({ eye, target, up, fov }) {
      if (!(fov > 0 && fov < 180)) throw new Error("setCamera: fov in (0, 180) degrees");
      this.camera = { eye: finite3(eye, "eye"), target: finite3(target, "target"), up: finite3(up, "up"), fov: +fov };
    }

    /** kind: "none", "sphere" (radius size, about the origin) or "box" ([-size, size]^3); cut: false shows the
     * surface inside the clip cut open (both sides seen, as SURFER), true the solid (f < 0) cut by the clip with
     * its cut face in the inside colour. */
    setClip({ kind, size, cut = false }) {
      if (!(kind in CLIPS)) throw new Error(`setClip: kind is one of ${Object.keys(CLIPS).join(", ")}`);
      if (!(size > 0 && Number.isFinite(size))) throw new Error("setClip: size > 0");
      this.clip = { kind, size: +size, cut: !!cut };
    }

    /** Up to MAX_LIGHTS lights, each {position: [x, y, z]} (a point in the world) or {direction: [r, u, b]}
     * (towards it, in the camera's right, up and back), with colour: RGB (any non-negative numbers). */
    setLights(lights) {
      if (!Array.isArray(lights) || lights.length > MAX_LIGHTS) throw new Error(`setLights: at most ${MAX_LIGHTS}`);
      this.lights = lights.map((l) => ({
        ...(l.position ? { position: finite3(l.position, "position") } : { direction: finite3(l.direction, "direction") }),
        colour: finite3(l.colour, "colour"),
      }));
    }

    /** Whether each light casts a shadow ray (the viewer's server picture has shadows). */
    setShadows(on) {
      this.shadows = !!on;
    }

    /** The Phong material: ambient, diffuse, specular, shininess. */
    setMaterial({ ambient, diffuse, specular, shininess }) {
      const m = [ambient, diffuse, specular, shininess].map(Number);
      if (!m.every((v) => Number.isFinite(v) && v >= 0)) throw new Error("setMaterial: four numbers >= 0");
      this.material = { ambient: m[0], diffuse: m[1], specular: m[2], shininess: m[3] };
    }

    /** outside (f > 0 side), inside (f < 0 side, and the clip's cut faces), background: RGB in [0, 1]. */
    setColours({ outside, inside, background }) {
      this.colours = {
        outside: finite3(outside ?? this.colours.outside, "outside"),
        inside: finite3(inside ?? this.colours.inside, "inside"),
        background: finite3(background ?? this.colours.background, "background"),
      };
    }

    /** Whether pixels float could not decide (IG_UNSURE) get the runtime's magenta checker. */
    setMarkUnsure(on) {
      this.markUnsure = !!on;
    }

    /** The drawing buffer's size in pixels (the canvas's CSS size is the page's business). */
    setSize(width, height) {
      width = Math.max(1, Math.min(8192, Math.round(width)));
      height = Math.max(1, Math.min(8192, Math.round(height)));
      if (width !== this.canvas.width) this.canvas.width = width;
      if (height !== this.canvas.height) this.canvas.height = height;
      this.width = width;
      this.height = height;
    }

    _uniforms(w, h, output = 0) {
      const gl = this.gl;
      const prog = this.prog;
      const loc = (n) => gl.getUniformLocation(prog, n);
      const c = this.camera;
      gl.uniform2f(loc("ig_page_size"), w, h);
      gl.uniform3fv(loc("ig_page_eye"), c.eye);
      gl.uniform3fv(loc("ig_page_look"), c.target);
      gl.uniform3fv(loc("ig_page_up"), c.up);
      gl.uniform1f(loc("ig_page_fov"), c.fov);
      gl.uniform1i(loc("ig_page_clip"), CLIPS[this.clip.kind]);
      gl.uniform1f(loc("ig_page_clip_size"), this.clip.size);
      gl.uniform1i(loc("ig_page_cut"), this.clip.cut ? 1 : 0);
      const m = this.material;
      if (!m) throw new Error("IgSurface.Renderer: setMaterial before the first draw");
      gl.uniform4f(loc("ig_page_material"), m.ambient, m.diffuse, m.specular, m.shininess);
      const pos = new Float32Array(4 * MAX_LIGHTS);
      const col = new Float32Array(3 * MAX_LIGHTS);
      this.lights.forEach((l, i) => {
        pos.set(l.position ? [...l.position, 1] : [...l.direction, 0], 4 * i);
        col.set(l.colour, 3 * i);
      });
      gl.uniform1i(loc("ig_page_nlights"), this.lights.length);
      gl.uniform4fv(loc("ig_page_light"), pos);
      gl.uniform3fv(loc("ig_page_light_colour"), col);
      gl.uniform1i(loc("ig_page_shadows"), this.shadows ? 1 : 0);
      gl.uniform1i(loc("ig_page_output"), output);
      gl.uniform3fv(loc("ig_page_outside"), this.colours.outside);
      gl.uniform3fv(loc("ig_page_inside"), this.colours.inside);
      gl.uniform3fv(loc("ig_page_background"), this.colours.background);
      gl.uniform1i(loc("ig_page_mark"), this.markUnsure ? 1 : 0);
      if (this.nparams > 0) gl.uniform1fv(loc(`${this.name}_params`), this.params);
    }

    /** Draw now. scale > 1 draws (width/scale) x (height/scale) pixels and stretches them over the canvas;
     * rows = [y0, y1] draws only those rows (image rows, 0 at the top) at full size. Returns the milliseconds
     * it took, the GPU's work included (it waits for it). */
    draw({ scale = 1, rows = null } = {}) {
      const gl = this.gl;
      if (!this.prog) return 0;
      const start = performance.now();
      const w = this.width;
      const h = this.height;
      gl.useProgram(this.prog);
      if (scale > 1) {
        const cw = Math.max(1, Math.ceil(w / scale));
        const ch = Math.max(1, Math.ceil(h / scale));
        this._coarseTarget(cw, ch);
        gl.bindFramebuffer(gl.FRAMEBUFFER, this.coarse.fbo);
        gl.disable(gl.SCISSOR_TEST);
        gl.viewport(0, 0, cw, ch);
        this._uniforms(cw, ch);
        gl.drawArrays(gl.TRIANGLES, 0, 3);
        gl.bindFramebuffer(gl.READ_FRAMEBUFFER, this.coarse.fbo);
        gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, null);
        gl.blitFramebuffer(0, 0, cw, ch, 0, 0, w, h, gl.COLOR_BUFFER_BIT, gl.NEAREST);
        gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      } else {
        gl.bindFramebuffer(gl.FRAMEBUFFER, null);
        gl.viewport(0, 0, w, h);
        this._uniforms(w, h);
        if (rows) {
          const y0 = Math.max(0, Math.min(h, rows[0] | 0));
          const y1 = Math.max(y0, Math.min(h, rows[1] | 0));
          gl.enable(gl.SCISSOR_TEST);
          gl.scissor(0, h - y1, w, y1 - y0);
        } else {
          gl.disable(gl.SCISSOR_TEST);
        }
        gl.drawArrays(gl.TRIANGLES, 0, 3);
        gl.disable(gl.SCISSOR_TEST);
      }
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4)); // wait for the GPU
      return performance.now() - start;
    }

    _coarseTarget(w, h) {
      const gl = this.gl;
      if (this.coarse && this.coarse.w === w && this.coarse.h === h) return;
      if (this.coarse) {
        gl.deleteFramebuffer(this.coarse.fbo);
        gl.deleteRenderbuffer(this.coarse.rb);
      }
      this.coarse = { ...this._offscreen(w, h), w, h };
    }

    /** An RGBA8 framebuffer of w x h pixels, bound: { fbo, rb } (the caller deletes them). */
    _offscreen(w, h) {
      const gl = this.gl;
      const rb = gl.createRenderbuffer();
      gl.bindRenderbuffer(gl.RENDERBUFFER, rb);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.RGBA8, w, h);
      const fbo = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.RENDERBUFFER, rb);
      return { fbo, rb };
    }

    /** What each pixel's ray found, at full size, drawn off screen (the canvas keeps its picture) in bands of
     * `band` rows (no single draw long enough for a GPU watchdog): RGBA bytes, bottom row first, red 255 where
     * it hit, green 255 where float could not decide (IG_UNSURE). */
    statusPixels(band = 32) {
      const gl = this.gl;
      const out = new Uint8Array(4 * this.width * this.height);
      if (!this.prog) return out;
      const w = this.width;
      const h = this.height;
      const { fbo, rb } = this._offscreen(w, h);
      gl.useProgram(this.prog);
      gl.viewport(0, 0, w, h);
      this._uniforms(w, h, 1);
      gl.enable(gl.SCISSOR_TEST);
      for (let y = 0; y < h; y += band) {
        gl.scissor(0, y, w, Math.min(band, h - y));
        gl.drawArrays(gl.TRIANGLES, 0, 3);
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4)); // finish this band first
      }
      gl.disable(gl.SCISSOR_TEST);
      gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, out);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.deleteFramebuffer(fbo);
      gl.deleteRenderbuffer(rb);
      return out;
    }

    /** The canvas's pixels, RGBA, bottom row first (gl.readPixels). */
    readPixels() {
      const gl = this.gl;
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      const out = new Uint8Array(4 * this.width * this.height);
      gl.readPixels(0, 0, this.width, this.height, gl.RGBA, gl.UNSIGNED_BYTE, out);
      return out;
    }
  }

  /** Redraws a Renderer only when something changed, one step per animation frame: a coarse frame first
   * (as coarse as it takes to fit `budget` ms), then, unless the view is still moving, the full frame in
   * bands of rows of about `budget` ms each, so the page stays responsive on a slow GPU. */
  class Progressive {
    constructor(renderer, { budget = 40, onStep = null, onIdle = null } = {}) {
      this.r = renderer;
      this.budget = budget;
      this.onStep = onStep;
      this.onIdle = onIdle;
      this.msPerPixel = null; // measured: the recent draws' cost per pixel (sizes the next band)
      this.framePerPixel = null; // measured: the last whole frame's cost per pixel (sizes the coarse frame)
      this.frameMs = 0;
      this.coarseDone = false;
      this.moving = false;
      this.row = 0;
      this.pending = false;
      this.idle = true;
      this.generation = 0; // counts invalidations, for tests and pages
      this.steps = 0; // draws made (coarse frames and bands)
    }

    /** Something changed; `moving`: more changes are coming (a drag), so draw coarse frames only. */
    invalidate(moving = false) {
      this.generation += 1;
      this.moving = !!moving;
      this.coarseDone = false;
      this.row = 0;
      this.idle = false;
      this._schedule();
    }

      /** Draw nothing more until the next invalidate (the page shows another picture). */
    stop() {
      this.moving = false;
      this.coarseDone = true;
      this.row = this.r.height;
      this.idle = true;
    }

    /** The drag ended: finish the frame at full size. */
    settle() {
      if (!this.moving) return;
      this.moving = false;
      this.idle = false;
      this._schedule();
    }

    _schedule() {
      if (this.pending) return;
      this.pending = true;
      requestAnimationFrame(() => {
        this.pending = false;
        this._step();
      });
    }

    _scale() {
      const per = this.framePerPixel ?? this.msPerPixel;
      if (per === null) return 8;
      const pixels = this.r.width * this.r.height;
      for (const s of [1, 2, 4, 8, 16]) {
        if ((per * pixels) / (s * s) <= this.budget) return s;
      }
      return 16;
    }

    // cost per pixel: up at once when a draw was dearer (the next band is no longer than budget allows), down
    // by halves (pixels differ in cost: rows through the surface are dearer than rows of background)
    _measure(ms, pixels) {
      const per = ms / Math.max(1, pixels);
      this.msPerPixel = this.msPerPixel === null || per > this.msPerPixel ? per : 0.5 * (this.msPerPixel + per);
    }

    _step() {
      const r = this.r;
      this.steps += 1;
      const w = r.width;
      const h = r.height;
      if (!this.coarseDone) {
        const scale = this._scale();
        const ms = r.draw({ scale });
        const pixels = Math.ceil(w / scale) * Math.ceil(h / scale);
        this._measure(ms, pixels);
        if (this.framePerPixel === null || scale === 1) this.framePerPixel = ms / pixels;
        this.coarseDone = true;
        this.row = scale === 1 ? h : 0; // a full-size "coarse" frame is the frame
        this.frameMs = 0;
      } else if (!this.moving && this.row < h) {
        // bands until about the budget is spent (an animation frame per band would leave most of it idle)
        let spent = 0;
        do {
          // never below the whole frame's average: rows of background must not make the next band too tall
          const per = Math.max(this.msPerPixel, this.framePerPixel ?? 0);
          const rows = Math.max(1, Math.min(h - this.row, Math.floor((this.budget - spent) / (per * w + 1e-9))));
          const ms = r.draw({ rows: [this.row, this.row + rows] });
          this._measure(ms, rows * w);
          this.row += rows;
          this.frameMs += ms;
          spent += ms;
        } while (this.row < h && spent < 0.5 * this.budget);
        if (this.row >= h) this.framePerPixel = this.frameMs / (w * h);
      }
      const done = this.coarseDone && (this.moving || this.row >= h);
      if (this.onStep) this.onStep(this);
      if (done) {
        this.idle = !this.moving;
        if (this.idle && this.onIdle) this.onIdle(this);
      } else {
        this._schedule();
      }
    }
  }

  return { Renderer, Progressive, fragmentSource, compileProgram, fullScreenTriangle, CLIPS, LIGHT, MAX_LIGHTS };
})();

if (typeof window !== "undefined") window.IgSurface = IgSurface;
