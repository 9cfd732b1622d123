// implgen share: a whole scene's page -- the scene's GLSL program (implgen.codegen.backends.glsl.scene) drawn by
// IgSceneRenderer (scenerender.js) with the scene's uniforms, turned by IgOrbit. Everything comes from the JSON
// block #ig-data that `implgen share SCENE.yaml` wrote; nothing is fetched.
"use strict";

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
