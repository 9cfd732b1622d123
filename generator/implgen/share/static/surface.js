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

// The sign of f where the ray enters the clip, certified (+1 outside the solid, -1 inside, 0 float cannot
// tell); outside the shape's box the solid is not there (a leaf is its solid cut by its box).
int ig_page_side(vec3 o, vec3 d, float t0, out float guess)
{
    vec3 p = o + t0 * d;
    vec3 lo, hi;
    IG_SHAPE_BOUNDS(lo, hi);
    guess = 1.0;
    if (any(lessThan(p, lo)) || any(greaterThan(p, hi))) {
        return 1;
    }
    vec3 e = (IG_ULP * (abs(t0 * d) + abs(p))) * (1.0 + IG_UP_REL) + IG_TINY;
    vec3 f = IG_SHAPE_RAA(ig_raa_var(p.x, 0.0, e.x), ig_raa_var(p.y, 0.0, e.y), ig_raa_var(p.z, 0.0, e.z));
    guess = f.x;
    return ig_raa_sign(f);
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

// Whether what the picture shows blocks o + t d for t in (0, tmax]: the surface inside the clip, or (cut
// solid) the solid where the ray enters the clip. status gets IG_UNSURE when float could not tell.
bool ig_page_blocked(vec3 o, vec3 d, float tmax, inout int status)
{
    float t0 = 0.0;
    float t1 = tmax;
    if (!ig_page_clip_ray(o, d, t0, t1)) {
        return false;
    }
    if (ig_page_cut == 1 && ig_page_clip != 0 && t0 > 0.0) {
        float guess;
        int side = ig_page_side(o, d, t0, guess);
        if (side < 0 || (side == 0 && guess < 0.0)) {
            status |= side == 0 ? IG_UNSURE : 0;
            return true;
        }
    }
    float t;
    vec3 n;
    int s = IG_SHAPE_HIT(o, d, t0, t1, t, n);
    status |= s & IG_UNSURE;
    return (s & IG_HIT) != 0;
}

// Whether f's sign at the point q is certain in float (its coordinates' rounding counted): a shadow ray that
// starts there does not start inside the surface's rounding noise.
bool ig_page_certain(vec3 q)
{
    vec3 e = IG_ULP * abs(q) * (1.0 + IG_UP_REL) + IG_TINY;
    return ig_raa_sign(IG_SHAPE_RAA(ig_raa_var(q.x, 0.0, e.x), ig_raa_var(q.y, 0.0, e.y), ig_raa_var(q.z, 0.0, e.z))) != 0;
}

// Two-sided shading as the C tracer's (runtime_c/tracer_shade.c): ambient, then for each light that faces the
// side seen, Lambert and a Blinn-Phong highlight times the light's colour (0 in shadow).
vec3 ig_page_shade(vec3 front, vec3 back, vec3 n, vec3 d, vec3 p, IgCamera cam, inout int status)
{
    vec3 u = normalize(d);
    bool behind = !(dot(n, u) < 0.0);
    vec3 nf = behind ? -n : n;
    vec3 base = behind ? back : front;
    vec3 colour = ig_page_material.x * base;
    // shadow rays leave a little off the surface (the float hit point is only that accurate), and further, up to
    // 64 times, until f's sign is certain there (a high degree's rounding noise is wide)
    float off = 4.0e-4 * (length(p) + length(p - cam.eye)) + 1.0e-6;
    vec3 start = p + nf * off;
    for (int k = 0; k < 3 && ig_page_shadows != 0 && !ig_page_certain(start); ++k) {
        off *= 4.0;
        start = p + nf * off;
    }
    for (int i = 0; i < IG_PAGE_MAX_LIGHTS; ++i) {
        if (i >= ig_page_nlights) {
            break;
        }
        vec4 lp = ig_page_light[i];
        vec3 l = lp.w > 0.5 ? lp.xyz - p : lp.x * cam.u + lp.y * cam.v + lp.z * cam.w;
        float ll = length(l);
        if (!(ll > 0.0)) {
            continue;
        }
        float ndl = dot(nf, l) / ll;
        if (ndl <= 0.0) {
            continue;
        }
        if (ig_page_shadows != 0) {
            vec3 towards = lp.w > 0.5 ? lp.xyz - start : l;
            if (ig_page_blocked(start, towards, lp.w > 0.5 ? 1.0 : ig_inf(), status)) {
                continue;
            }
        }
        vec3 hv = normalize(l / ll - u);
        float ndh = dot(nf, hv);
        float spec = ndh > 0.0 ? ig_page_material.z * pow(ndh, ig_page_material.w) : 0.0;
        colour += ig_page_light_colour[i] * (ig_page_material.y * base * ndl + spec);
    }
    return colour;
}

void main()
{
    vec2 pixel = vec2(gl_FragCoord.x, ig_page_size.y - gl_FragCoord.y);
    IgCamera cam = ig_camera(ig_page_eye, ig_page_look, ig_page_up, ig_page_fov, ig_page_size);
    vec3 d = ig_camera_dir(cam, pixel, ig_page_size);
    float t0 = 0.0;
    float t1 = ig_inf();
    bool open = ig_page_clip_ray(cam.eye, d, t0, t1);
    int status = 0;
    vec3 rgb = ig_page_background;
    if (open) {
        int side = 1;
        float guess = 1.0;
        if (ig_page_cut == 1 && ig_page_clip != 0 && t0 > 0.0) {
            side = ig_page_side(cam.eye, d, t0, guess);
        }
        if (side < 0 || (side == 0 && guess < 0.0)) { // the cut face: the solid's inside, flat on the clip
            status = IG_HIT | (side == 0 ? IG_UNSURE : 0);
            vec3 p = cam.eye + t0 * d;
            rgb = ig_page_shade(ig_page_inside, ig_page_inside, ig_page_clip_normal(p), d, p, cam, status);
        } else {
            float t;
            vec3 n;
            status = IG_SHAPE_HIT(cam.eye, d, t0, t1, t, n) | (side == 0 ? IG_UNSURE : 0);
            if ((status & IG_HIT) != 0) {
                rgb = ig_page_shade(ig_page_outside, ig_page_inside, n, d, cam.eye + t * d, cam, status);
            }
        }
    }
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
