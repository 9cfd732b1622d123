// implgen share: a whole scene's page -- the scene's GLSL program (implgen.codegen.backends.glsl.scene) drawn by
// IgSurface's renderer with the scene's uniforms, turned by IgOrbit. Everything comes from the JSON block #ig-data
// that `implgen share SCENE.yaml` wrote; nothing is fetched.
"use strict";

/** IgSurface.Renderer drawing a scene program: its own program and uniforms, the renderer's drawing and
 * progressive redraw. The camera's basis is worked out here in double, as the C tracer's (tracer_render.c). */
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
    gl.uniform1f(loc("ig_scene_output"), output);
  }
}

(() => {
  const $ = (id) => document.getElementById(id);
  const data = JSON.parse($("ig-data").textContent);
  const canvas = $("ig-canvas");
  const status = (text) => {
    $("ig-status").textContent = text;
  };
  const fail = (text) => {
    $("ig-message").textContent = text;
    $("ig-message").hidden = false;
    window.implgenScene = { error: text };
  };

  let r;
  try {
    r = new IgSceneRenderer(canvas);
  } catch (err) {
    fail(`${err.message || err}: this page needs a browser with WebGL2.`);
    return;
  }
  status("compiling the shader...");
  requestAnimationFrame(() => setTimeout(start, 0)); // after the status line is on screen

  function start() {
    const log = r.setSceneProgram(data.header, data.program);
    if (log) {
      fail(`the shader did not compile on this browser: ${log.split("\n")[0]}`);
      console.error(log);
      return;
    }
    const [, renderer] = r.info();
    const orbit = new IgOrbit(data.orbit);
    let fixed = null; // [w, h]: a drawing buffer size that does not follow the window
    let started = 0;
    const progressive = new IgSurface.Progressive(r, {
      onStep: (p) => {
        if (!p.idle) status(p.moving ? "moving" : `drawing... ${Math.round((100 * p.row) / r.height)} %`);
      },
      onIdle: () => status(`${r.width} x ${r.height} in ${Math.round(performance.now() - started)} ms -- ${renderer}`),
    });

    function fit() {
      if (fixed) {
        r.setSize(fixed[0], fixed[1]);
        return;
      }
      const dpr = Math.min(window.devicePixelRatio || 1, 2);
      const box = canvas.getBoundingClientRect();
      r.setSize(Math.max(1, box.width * dpr), Math.max(1, box.height * dpr));
    }

    function changed(moving) {
      r.setCamera(orbit.camera());
      r.setMarkUnsure($("ig-unsure").checked);
      started = performance.now();
      progressive.invalidate(moving);
    }

    $("ig-unsure").addEventListener("change", () => changed(false));
    $("ig-reset").addEventListener("click", () => {
      orbit.reset();
      changed(false);
    });
    canvas.addEventListener("webglcontextlost", (e) => {
      e.preventDefault();
      fail("the browser took the GPU away from this page (WebGL context lost): reload the page to draw again.");
    });
    orbit.attach(canvas, changed);
    window.addEventListener("resize", () => {
      if (!fixed) {
        fit();
        changed(false);
      }
    });
    fit();
    changed(false);

    // For tests and for people poking at the page from the console.
    window.implgenScene = {
      renderer: r,
      orbit,
      progressive,
      idle: () => progressive.idle,
      /** Draw at exactly w x h pixels from now on (the canvas keeps its CSS size). */
      fixSize(w, h) {
        fixed = [w, h];
        fit();
        changed(false);
      },
    };
  }
})();
