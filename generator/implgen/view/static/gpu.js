// implgen view: the GPU preview (docs/viewer.md, "The GPU preview"). Where the browser has WebGL2, the page
// draws the live picture itself while the view moves, with the shape's generated GLSL on the shared page's
// renderer (IgSurface, share/static/surface.js) and camera (IgOrbit); the server's double-precision frame
// replaces it when the view rests. A scene file is drawn by its whole GLSL program (IgSceneRenderer,
// share/static/scenerender.js: the scene tracer, the picked leaf's values folded in, so an edit asks for a new
// program) while moving and at rest; at rest the page keeps the GPU's picture and asks the server for the pixels
// the GLSL flagged "not sure", traced in double (view/fix.py), and puts them in ("fixed"). "compare with server"
// paints, over the server's frame, the pixels where the GPU's picture differs from it and the pixels the GLSL
// could not decide (with it ticked a scene's rest is the server's frame). Without WebGL2, with a shader the
// browser will not compile, or past the GLSL budget of a scene (the server says why), the page is the server's
// alone, exactly as without this file. app.js calls: hello, shape, program, active, draw, fixesRest, fixed,
// serverFrame.
"use strict";

const ImplgenGpu = (() => {
  const DIFF_LEVELS = 8; // a pixel differs when it is this many levels (of 255) outside the server's 3x3 range
  const DIFFER = [255, 48, 48, 255]; // the compare overlay: red where the pictures differ,
  const UNSURE = [0, 230, 255, 255]; // cyan where the GLSL could not decide, yellow where both
  const BOTH = [255, 230, 0, 255];

  function create({ stage, view, note, toggle, compare, status = null, redraw = () => {}, serverRest = () => {} }) {
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
      // a scene file: its renderer, redraw, program (msg.scene) and the key of the values it was built for
      isScene: false, sceneRenderer: null, sceneProgressive: null, scene: null, programKey: "", wantKey: "",
      askId: 0, askKey: "", asks: new Map(), seq: -1, fix: null, fixes: 0,
    };
    const R = () => (g.isScene ? g.sceneRenderer : g.renderer); // the renderer of what is drawn
    const P = () => (g.isScene ? g.sceneProgressive : g.progressive);
    // which path draws, said on the page (and in #view's data-path, for tests)
    function say() {
      let why = "";
      if (g.failure) why = g.failure;
      else if (!toggle.checked) {
        why = g.software ? "WebGL2 here is a software renderer, slower than the server: tick GPU preview to use it"
          : "GPU preview off";
      } else if (g.reason) why = g.reason;
      else if (!active()) why = g.isScene ? "waiting for the scene's GLSL" : "waiting for the shape's GLSL";
      // the server's note on the shape's GLSL (its Chebyshev form cut by the GLSL budget) while the GPU draws it
      const basis = g.basis ? `; ${g.basis}` : "";
      const rest = g.isScene ? (compare.checked ? "the server at rest" : "at rest too, the server fixing the pixels "
        + "it flags") : "the server at rest";
      const what = g.isScene && g.scene ? ` the scene (${g.scene.what}),` : "";
      note.textContent = active() ? `drawing:${what} the GPU while the view moves (${g.renderer.info()[1]}), ${rest}${basis}`
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
      if (g.isScene) {
        return !!(g.sceneRenderer && !g.failure && toggle.checked && g.scene && g.programId === g.shapeId
          && g.programKey === g.wantKey && !g.reason);
      }
      return !!(g.renderer && !g.failure && toggle.checked && g.shape && g.programId === g.shapeId && !g.reason);
    }

    function stop() {
      if (g.progressive) g.progressive.stop();
      if (g.sceneProgressive) g.sceneProgressive.stop();
      g.fix = null;
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
      g.isScene = msg.mode === "scene";
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
      g.programKey = ""; // a scene's program is asked for at the next draw (its values are in the view)
      g.askKey = "";
      stop();
      if (!g.isScene) ask();
      say();
    }

    /** The `glsl` message: the shape's GLSL, compiled now, or why the server draws every frame. */
    function program(msg) {
      if (msg.shape_id !== g.shapeId || !g.renderer || !g.runtime) return;
      if (g.isScene) { sceneProgram(msg); return; }
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
          g.progressive = g.progressive || new IgSurface.Progressive(g.renderer, { onStep: stepped });
        }
      }
      say();
    }

    // ---------------------------------------------------------------- a scene file's program
    // what a scene's program depends on that the page sets: the picked leaf's values and its clip
    const sceneKey = (v) => JSON.stringify([g.shapeId, v.values, v.options.clip, v.options.clip_size]);

    function askScene(v, key) {
      g.askId += 1;
      g.askKey = key;
      g.asks.set(g.askId, key);
      send({ type: "glsl", ask: g.askId, values: v.values });
    }

    /** A scene's `glsl` message (the answer to the latest ask only): its program compiled (not again when the
     * text is the one compiled), or why the server draws. */
    function sceneProgram(msg) {
      const key = g.asks.get(msg.ask);
      if (msg.ask !== g.askId || key === undefined) return; // a newer ask is on its way
      g.asks.clear();
      g.reason = msg.reason ? msg.reason : "";
      if (!msg.reason) {
        try {
          g.sceneRenderer = g.sceneRenderer || new IgSceneRenderer(glCanvas); // the canvas's one WebGL2 context
        } catch (err) {
          g.reason = `GPU preview off: ${err.message || err}`;
        }
      }
      if (!g.reason) {
        const s = msg.scene;
        const same = g.scene && g.scene.header === s.header && g.scene.program === s.program;
        const log = same ? "" : g.sceneRenderer.setSceneProgram(s.header, s.program);
        if (log) {
          g.reason = `GPU preview off: the scene's shader did not compile on this browser: ${log.split("\n")[0]}`;
          g.scene = null;
          console.error(log);
        } else {
          g.scene = s;
          g.programKey = key;
          g.programId = msg.shape_id;
          g.sceneProgressive = g.sceneProgressive || new IgSurface.Progressive(g.sceneRenderer, {
            onStep: stepped, onIdle: rested,
          });
        }
      }
      say();
      if (active()) redraw(); // the program is here: the view drawn with it
    }

    /** A step of either program's progressive draw: counted, and said on the status line. */
    function stepped(p) {
      g.frames += 1;
      glCanvas.dataset.frames = g.frames;
      if (status && view.dataset.shown === "gpu") { // the status line: what the GPU draws now
        const r = p.r;
        const done = p.moving ? "while moving" : p.row >= r.height ? "done" : `${Math.round((100 * p.row) / r.height)} %`;
        status.textContent = `GPU ${r.width} x ${r.height}, ${done}`;
      }
    }

    function sceneApply({ orbit, options }) {
      const r = g.sceneRenderer;
      r.setSize(view.width, view.height);
      r.setCamera(new IgOrbit(orbit).camera());
      r.setColours({ background: options.background });
      r.setSceneLights(options.lights === "scene" ? g.scene.lights : lights(options.lights, orbit));
      r.setMarkUnsure(false);
    }

    // ---------------------------------------------------------------- a scene's rest: the flagged pixels
    /** Whether the rest of the view drawn now is the GPU's, fixed by the server (else the server's frame). */
    function fixesRest() {
      return g.isScene && active() && !compare.checked;
    }

    // the full frame is drawn at rest: its flagged pixels asked of the server, or none to ask
    function rested() {
      if (!fixesRest() || !g.view || view.dataset.shown !== "gpu") return;
      const r = g.sceneRenderer;
      if (r.gl.isContextLost()) return;
      const w = r.width, h = r.height;
      const st = r.statusPixels();
      const flagged = [];
      for (let gy = 0; gy < h; ++gy) {
        for (let x = 0; x < w; ++x) if (st[4 * (gy * w + x) + 1] > 127) flagged.push((h - 1 - gy) * w + x);
      }
      const most = g.runtime.fix;
      if (flagged.length > most.pixels * most.parts) { // too many: the server's frame, as before
        g.fix = null;
        serverRest();
        return;
      }
      flagged.sort((a, b) => a - b);
      const parts = [];
      for (let i = 0; i < flagged.length; i += most.pixels) parts.push(flagged.slice(i, i + most.pixels));
      g.fix = { seq: g.seq, w, h, parts, got: new Array(parts.length).fill(null), left: parts.length };
      const v = g.view;
      parts.forEach((pixels, part) => send({ type: "fix", seq: g.seq, width: w, height: h, values: v.values,
        orbit: v.orbit, options: v.options, part, pixels }));
      if (!parts.length) composite();
    }

    /** A KIND_FIX frame: the server's colours of one part's pixels (3 bytes each, in the order asked). */
    function fixed(seq, part, w, h, bytes) {
      const f = g.fix;
      if (!f || seq !== f.seq || w !== f.w || h !== f.h || !(part < f.parts.length) || f.got[part]) return;
      if (bytes.length !== 3 * f.parts[part].length) return;
      f.got[part] = bytes;
      f.left -= 1;
      if (f.left === 0) composite();
    }

    // the GPU's picture onto the page's canvas, the server's pixels put in; the page's canvas shown
    function composite() {
      const f = g.fix;
      g.fix = null;
      if (!f || view.width !== f.w || view.height !== f.h) return;
      const ctx = view.getContext("2d");
      ctx.drawImage(glCanvas, 0, 0);
      const img = ctx.getImageData(0, 0, f.w, f.h);
      let n = 0;
      f.parts.forEach((pixels, part) => pixels.forEach((p, i) => {
        img.data.set(f.got[part].subarray(3 * i, 3 * i + 3), 4 * p);
        n += 1;
      }));
      ctx.putImageData(img, 0, 0);
      glCanvas.hidden = true;
      g.fixes += 1;
      view.dataset.shown = "fixed";
      view.dataset.fixed = n;
      view.dataset.fixSeq = f.seq;
      if (status) status.textContent = `GPU ${f.w} x ${f.h}, ${n} pixels from the server`;
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

    /** Draw the view (moving: more is coming, coarse frames while the GPU is slow); `seq`: the page's request. */
    function draw(v, moving, seq = -1) {
      if (g.isScene) {
        g.wantKey = sceneKey(v); // a scene's program is for the values it was asked with
        const can = g.renderer && !g.failure && toggle.checked && g.runtime;
        if (can && g.wantKey !== g.programKey && g.wantKey !== g.askKey) askScene(v, g.wantKey);
      }
      if (!active()) return false;
      const key = JSON.stringify(v);
      // at rest on the view the server's refined picture (or a scene's fixed one) already shows: keep that
      if (!moving && key === g.key && ["server", "fixed"].includes(view.dataset.shown)) return true;
      g.seq = seq;
      g.fix = null;
      try {
        if (g.isScene) sceneApply(v);
        else apply(v);
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
      if (!moving && P().moving && key === g.key) P().settle();
      else P().invalidate(moving);
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
      const r = R();
      if (r.gl.isContextLost()) { overlay.hidden = true; return; } // its pixels would read as zeros
      if (g.isScene) sceneApply(g.view);
      else apply(g.view);
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
      if (toggle.checked && g.programId !== g.shapeId && !g.reason && !g.isScene) ask();
      if (toggle.checked && g.isScene) redraw(); // a scene asks for its program at the next draw
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
    const api = { hello, shape, program, active, draw, fixesRest, fixed, serverFrame, state: g, renderer: () => R() };
    window.implgenGpu = api; // for tests and for the curious, in the browser's console
    return api;
  }

  return { create, DIFF_LEVELS };
})();

if (typeof window !== "undefined") window.ImplgenGpu = ImplgenGpu;
