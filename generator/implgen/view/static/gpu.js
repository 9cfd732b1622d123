// implgen view: the GPU preview (docs/viewer.md, "The GPU preview"). Where the browser has WebGL2, the page
// draws the live picture itself while the view moves, with the shape's generated GLSL on the shared page's
// renderer (IgSurface, share/static/surface.js) and camera (IgOrbit); the server's double-precision frame
// replaces it when the view rests. "compare with server" paints, over the server's frame, the pixels where the
// GPU's picture differs from it and the pixels the GLSL could not decide. Without WebGL2, with a shader the
// browser will not compile, or for a scene the GLSL page cannot draw (the server says why), the page is the
// server's alone, exactly as without this file. app.js calls: hello, shape, program, active, draw, serverFrame.
"use strict";

const ImplgenGpu = (() => {
  const DIFF_LEVELS = 8; // a pixel differs when it is this many levels (of 255) outside the server's 3x3 range
  const DIFFER = [255, 48, 48, 255]; // the compare overlay: red where the pictures differ,
  const UNSURE = [0, 230, 255, 255]; // cyan where the GLSL could not decide, yellow where both
  const BOTH = [255, 230, 0, 255];

  function create({ stage, view, note, toggle, compare, status = null }) {
    const glCanvas = document.createElement("canvas");
    glCanvas.id = "gpu-view";
    glCanvas.hidden = true;
    const overlay = document.createElement("canvas");
    overlay.id = "compare-view";
    overlay.hidden = true;
    stage.insertBefore(overlay, view.nextSibling);
    stage.insertBefore(glCanvas, view.nextSibling);
    const g = {
      renderer: null, progressive: null, failure: "", reason: "", software: false, runtime: null, basis: "",
      shape: null, shapeId: -1, programId: -1, view: null, key: "", frames: 0, compared: null,
    };
    // which path draws, said on the page (and in #view's data-path, for tests)
    function say() {
      let why = "";
      if (g.failure) why = g.failure;
      else if (!toggle.checked) {
        why = g.software ? "WebGL2 here is a software renderer, slower than the server: tick GPU preview to use it"
          : "GPU preview off";
      } else if (g.reason) why = g.reason;
      else if (!active()) why = "waiting for the shape's GLSL";
      // the server's note on the shape's GLSL (its Chebyshev form cut by the GLSL budget) while the GPU draws it
      const basis = g.basis ? `; ${g.basis}` : "";
      note.textContent = active() ? `drawing: the GPU while the view moves (${g.renderer.info()[1]}), the server at rest${basis}`
        : `drawing: the server (${why})`;
      view.dataset.path = active() ? "gpu" : "server";
    }
    try {
      g.renderer = new IgSurface.Renderer(glCanvas);
      // a CPU pretending to be a GPU (SwiftShader, llvmpipe): the server's tracer is faster; off unless ticked
      g.software = /swiftshader|llvmpipe|software/i.test(g.renderer.info()[1] || "");
      if (g.software) toggle.checked = false;
    } catch (err) {
      g.failure = `GPU preview off: ${err.message || err}`;
      toggle.checked = false;
      toggle.disabled = true;
      compare.disabled = true;
    }

    function active() {
      return !!(g.renderer && !g.failure && toggle.checked && g.shape && g.programId === g.shapeId && !g.reason);
    }

    function stop() {
      if (g.progressive) g.progressive.stop();
      glCanvas.hidden = true;
    }

    // the page's send(): ask for the shape's GLSL when the preview can use it
    let send = () => {};
    function ask() {
      if (g.renderer && !g.failure && toggle.checked && g.runtime) send({ type: "glsl" });
    }

    /** The hello message: the runtime, the light presets and the material; the first shape. */
    function hello(msg, sendMessage) {
      send = sendMessage;
      g.runtime = msg.gpu ? msg.gpu : null;
      shape(msg);
    }

    /** A new shape accepted (or another object of a scene picked): nothing drawn on the GPU until its GLSL. */
    function shape(msg) {
      g.shapeId = msg.shape_id;
      g.shape = null;
      g.view = null;
      g.key = ""; // the next view is drawn, even one equal to the last shape's
      g.reason = "";
      g.basis = "";
      stop();
      ask();
      say();
    }

    /** The `glsl` message: the shape's GLSL, compiled now, or why the server draws every frame. */
    function program(msg) {
      if (msg.shape_id !== g.shapeId || !g.renderer || !g.runtime) return;
      g.reason = "";
      g.basis = typeof msg.note === "string" ? msg.note : "";
      if (msg.reason) {
        g.reason = msg.reason;
      } else {
        const log = g.renderer.setEquationProgram({
          name: msg.glsl_name, shape: msg.shape, runtime: g.runtime.runtime, header: g.runtime.header,
          params: msg.params.length,
        });
        if (log) {
          g.reason = `GPU preview off: the shader did not compile on this browser: ${log.split("\n")[0]}`;
          console.error(log);
        } else {
          g.shape = msg;
          g.programId = msg.shape_id;
          g.progressive = g.progressive || new IgSurface.Progressive(g.renderer, {
            onStep: (p) => {
              g.frames += 1;
              glCanvas.dataset.frames = g.frames;
              if (status && view.dataset.shown === "gpu") { // the status line: what the GPU draws now
                const r = g.renderer;
                const done = p.moving ? "while moving" : p.row >= r.height ? "done" : `${Math.round((100 * p.row) / r.height)} %`;
                status.textContent = `GPU ${r.width} x ${r.height}, ${done}`;
              }
            },
          });
        }
      }
      say();
    }

    function lights(preset, orbit) {
      const o = new IgOrbit(orbit);
      const { right, up, back } = o.basis();
      const d = orbit.distance;
      const presets = g.runtime.lights;
      return (Object.hasOwn(presets, preset) ? presets[preset] : presets.studio).map((l) => ({
        position: l.frame === "camera"
          ? orbit.target.map((t, i) => t + 2 * d * (l.at[0] * right[i] + l.at[1] * up[i] + l.at[2] * back[i]))
          : orbit.target.map((t, i) => t + d * l.at[i]),
        colour: l.colour,
      }));
    }

    function apply({ orbit, values, options }) {
      const r = g.renderer;
      r.setSize(view.width, view.height);
      r.setParams(g.shape.params.map((name) => (Object.hasOwn(values, name) ? values[name] : NaN))); // NaN: refused
      r.setCamera(new IgOrbit(orbit).camera());
      r.setClip({ kind: options.clip, size: options.clip_size, cut: options.cut });
      r.setColours({ outside: options.color, inside: options.inside, background: options.background });
      r.setLights(lights(options.lights, orbit));
      r.setMaterial(g.runtime.material);
      r.setShadows(true);
      r.setMarkUnsure(false);
    }

    /** Draw the view (moving: more is coming, coarse frames while the GPU is slow). */
    function draw(v, moving) {
      if (!active()) return false;
      const key = JSON.stringify(v);
      // at rest on the view the server's refined picture already shows (a second request for it): keep that
      if (!moving && key === g.key && view.dataset.shown === "server") return true;
      try {
        apply(v);
      } catch (err) { // a view the renderer refuses (it should not happen): the server draws, and says so
        g.reason = `GPU preview off: ${err.message || err}`;
        stop();
        say();
        return false;
      }
      g.view = v;
      glCanvas.hidden = false;
      overlay.hidden = true;
      view.dataset.shown = "gpu";
      if (!moving && g.progressive.moving && key === g.key) g.progressive.settle();
      else g.progressive.invalidate(moving);
      g.key = key;
      return true;
    }

    /** The server's refined frame is on the page's canvas: it replaces the GPU's picture (and is compared). */
    function serverFrame(ctx2d, final) {
      view.dataset.shown = "server";
      if (!active() || !g.view) { stop(); overlay.hidden = true; return; }
      stop();
      if (compare.checked && final) runCompare(ctx2d); // the 4-sample frame only: one compare a rest
      else overlay.hidden = true;
    }

    // The GPU's full frame of the view the server drew, against the server's pixels: a pixel differs when a
    // channel is more than DIFF_LEVELS outside the range of the server's 3x3 neighbourhood (so a silhouette
    // the server antialiased, at 4 samples a pixel, is not a difference; the GPU draws 1, at the centre).
    function runCompare(ctx2d) {
      const r = g.renderer;
      if (r.gl.isContextLost()) { overlay.hidden = true; return; } // its pixels would read as zeros
      apply(g.view);
      for (let y = 0; y < r.height; y += 32) r.draw({ rows: [y, y + 32] }); // bands: no draw long enough for a watchdog
      const w = r.width, h = r.height;
      if (w !== view.width || h !== view.height) return;
      const mine = r.readPixels();
      const status = r.statusPixels();
      const server = ctx2d.getImageData(0, 0, w, h).data;
      overlay.width = w; overlay.height = h;
      const out = new ImageData(w, h);
      let differ = 0, unsure = 0, unflagged = 0;
      for (let y = 0; y < h; ++y) {
        const gy = h - 1 - y; // GL rows: bottom first
        for (let x = 0; x < w; ++x) {
          const gi = 4 * (gy * w + x), i = 4 * (y * w + x);
          let excess = 0;
          for (let c = 0; c < 3; ++c) {
            let lo = 255, hi = 0;
            for (let yy = Math.max(0, y - 1); yy <= Math.min(h - 1, y + 1); ++yy) {
              for (let xx = Math.max(0, x - 1); xx <= Math.min(w - 1, x + 1); ++xx) {
                const s = server[4 * (yy * w + xx) + c];
                if (s < lo) lo = s;
                if (s > hi) hi = s;
              }
            }
            excess = Math.max(excess, lo - mine[gi + c], mine[gi + c] - hi);
          }
          const d = excess > DIFF_LEVELS, u = status[gi + 1] > 127;
          if (d) differ += 1;
          if (u) unsure += 1;
          if (d && !u) unflagged += 1;
          if (d || u) out.data.set(d && u ? BOTH : d ? DIFFER : UNSURE, i);
        }
      }
      overlay.getContext("2d").putImageData(out, 0, 0);
      overlay.hidden = false;
      g.compared = { width: w, height: h, differ, unsure, unflagged };
      overlay.dataset.seq = view.dataset.seq;
      overlay.dataset.differ = differ;
      overlay.dataset.unsure = unsure;
      const pc = (n) => `${((100 * n) / (w * h)).toFixed(2)} %`;
      note.textContent = `compare: ${pc(differ)} of the pixels differ from the server's (red), ${pc(unsure)} not sure `
        + "on the GPU (cyan; yellow: both)";
    }

    toggle.addEventListener("change", () => {
      if (!toggle.checked) { stop(); overlay.hidden = true; }
      if (toggle.checked && g.programId !== g.shapeId && !g.reason) ask();
      say();
    });
    compare.addEventListener("change", () => {
      if (!compare.checked) { overlay.hidden = true; say(); return; }
      // ticked while the server's picture is shown: compare it now, not at the next one
      if (active() && g.view && view.dataset.shown === "server") runCompare(view.getContext("2d"));
    });
    glCanvas.addEventListener("webglcontextlost", (e) => {
      e.preventDefault();
      g.failure = "GPU preview off: the browser took the GPU away (WebGL context lost)";
      stop();
      overlay.hidden = true;
      say();
    });
    say();
    const api = { hello, shape, program, active, draw, serverFrame, state: g, renderer: () => g.renderer };
    window.implgenGpu = api; // for tests and for the curious, in the browser's console
    return api;
  }

  return { create, DIFF_LEVELS };
})();

if (typeof window !== "undefined") window.ImplgenGpu = ImplgenGpu;
