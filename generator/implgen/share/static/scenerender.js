// implgen: IgSceneRenderer, IgSurface's renderer drawing a scene's GLSL program (implgen.codegen.backends.glsl.scene)
// with the scene's uniforms. The shared scene page (scene.js) and the viewer's GPU preview (view/static/gpu.js)
// draw with it; no page in it.
"use strict";

/** IgSurface.Renderer drawing a scene program: its own program and uniforms, the renderer's drawing, status pass
 * and progressive redraw. The camera's basis is worked out here in double, as the C tracer's (tracer_render.c).
 * A viewer's program (live lights) takes its lights and background from setLights and setColours. */
class IgSceneRenderer extends IgSurface.Renderer {
  /** The scene's program: header and body (header + body is the fragment shader). '' or the compiler's log. */
  setSceneProgram(header, body) {
    if (typeof header !== "string" || !header.startsWith("#version 300 es\n")) return "no GLSL ES 3.00 header";
    try {
      const prog = IgSurface.compileProgram(this.gl, header + body);
      if (this.prog) this.gl.deleteProgram(this.prog);
      this.prog = prog;
    } catch (err) {
      return String(err.message || err);
    }
    this.fragment = header + body;
    return "";
  }

  /** A live program's lights: each {position: [x, y, z], colour: [r, g, b]}, as many as it has slots at most. */
  setSceneLights(lights) {
    if (!Array.isArray(lights)) throw new Error("setSceneLights: a list");
    const finite3 = (v) => Array.isArray(v) && v.length === 3 && v.every(Number.isFinite);
    if (!lights.every((l) => finite3(l.position) && finite3(l.colour))) {
      throw new Error("setSceneLights: each light a position and a colour, three numbers each");
    }
    this.sceneLights = lights.map((l) => ({ position: l.position.map(Number), colour: l.colour.map(Number) }));
  }

  /** output: 0 the colour; 1 (the renderer's status pass, statusPixels) the status bytes: red a hit, green not
   * sure, blue the object + 1. */
  _uniforms(w, h, output = 0) {
    const gl = this.gl;
    const loc = (n) => gl.getUniformLocation(this.prog, n);
    const c = this.camera;
    const sub = (a, b) => a.map((v, i) => v - b[i]);
    const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    const unit = (a) => {
      const l = Math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      return l > 0 ? a.map((v) => v / l) : null;
    };
    const back = unit(sub(c.eye, c.target)) || [0, 0, 1];
    const right = unit(cross(c.up, back)) || unit(cross(Math.abs(back[0]) > 0.9 ? [0, 1, 0] : [1, 0, 0], back));
    const up = cross(back, right);
    const tanHalf = Math.tan((0.5 * c.fov * Math.PI) / 180);
    gl.uniform2f(loc("ig_scene_size"), w, h);
    gl.uniform3fv(loc("ig_scene_eye"), c.eye);
    gl.uniform3fv(loc("ig_scene_right"), right.map((v) => v * tanHalf * (w / h)));
    gl.uniform3fv(loc("ig_scene_upv"), up.map((v) => v * tanHalf));
    gl.uniform3fv(loc("ig_scene_back"), back);
    gl.uniform1f(loc("ig_scene_mark"), this.markUnsure ? 1 : 0);
    gl.uniform1f(loc("ig_scene_output"), output === 1 ? 2 : output);
    this._liveUniforms(loc);
  }

  /** A live program's lights and background (a shared page's program has none of these uniforms). */
  _liveUniforms(loc) {
    const gl = this.gl;
    const at = loc("ig_scene_nlights");
    if (at === null) return;
    const lights = this.sceneLights || [];
    const pos = new Float32Array(3 * Math.max(1, lights.length));
    const col = new Float32Array(3 * Math.max(1, lights.length));
    lights.forEach((l, i) => {
      pos.set(l.position, 3 * i);
      col.set(l.colour, 3 * i);
    });
    gl.uniform1i(at, lights.length);
    if (lights.length) {
      gl.uniform3fv(loc("ig_light_pos"), pos);
      gl.uniform3fv(loc("ig_light_color"), col);
    }
    gl.uniform3fv(loc("ig_scene_background"), this.colours.background);
  }
}

if (typeof window !== "undefined") window.IgSceneRenderer = IgSceneRenderer;
