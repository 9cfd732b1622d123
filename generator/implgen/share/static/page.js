// implgen share: the shared page's own controls, around IgSurface (the drawing) and IgOrbit (the camera).
// Everything it shows comes from the JSON block #ig-data that `implgen share` wrote; nothing is fetched.
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
    window.implgenShare = { error: text };
  };

  let r;
  try {
    r = new IgSurface.Renderer(canvas);
  } catch (err) {
    fail(`${err.message || err}: this page needs a browser with WebGL2.`);
    return;
  }
  status("compiling the shader...");
  // compiled after the status line is on screen: a high-degree shape can take the compiler seconds
  requestAnimationFrame(() => setTimeout(start, 0));

  function start() {
    const log = r.setEquationProgram({
      name: data.glsl_name, shape: data.shape, runtime: data.runtime, header: data.header, params: data.params.length,
    });
    r.setMaterial(data.material); // the viewer's (share/page.py MATERIAL)
    if (log) {
      fail(`the shader did not compile on this browser: ${log.split("\n")[0]}`);
      console.error(log);
      return;
    }
    const [, renderer] = r.info();

    const orbit = new IgOrbit(data.orbit);
    const values = data.params.map((p) => p.value);
    const fromHex = (hex) => [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255);
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

    function apply() {
      r.setParams(values);
      r.setCamera(orbit.camera());
      const size = parseFloat($("ig-clip-size").value);
      r.setClip({
        kind: $("ig-clip").value,
        size: size > 0 && Number.isFinite(size) ? size : data.clip.size,
        cut: $("ig-cut").checked,
      });
      r.setColours({
        outside: fromHex($("ig-outside").value),
        inside: fromHex($("ig-inside").value),
        background: fromHex($("ig-background").value),
      });
      r.setMarkUnsure($("ig-unsure").checked);
    }

    // moving: more changes follow (a drag, a slider being dragged): coarse frames only until it rests
    function changed(moving) {
      apply();
      if (!moving && progressive.moving) {
        progressive.settle();
        return;
      }
      started = performance.now();
      progressive.invalidate(moving);
    }

    // ---------------------------------------------------------------- the params' sliders
    for (const slider of document.querySelectorAll("input[data-param]")) {
      const i = parseInt(slider.dataset.param, 10);
      const shown = $(`ig-value-${i}`);
      const show = () => {
        shown.textContent = Number(values[i].toPrecision(6)).toString();
      };
      slider.addEventListener("input", () => {
        values[i] = parseFloat(slider.value);
        show();
        changed(true);
      });
      slider.addEventListener("change", () => changed(false));
      show();
    }

    // ---------------------------------------------------------------- look
    for (const id of ["ig-outside", "ig-inside", "ig-background", "ig-clip-size"]) {
      $(id).addEventListener("input", () => changed(true));
      $(id).addEventListener("change", () => changed(false));
    }
    for (const id of ["ig-clip", "ig-cut", "ig-unsure"]) $(id).addEventListener("change", () => changed(false));
    $("ig-reset").addEventListener("click", () => {
      orbit.reset();
      changed(false);
    });
    $("ig-save").addEventListener("click", () => {
      const a = document.createElement("a");
      a.href = canvas.toDataURL("image/png");
      a.download = `${data.name}.png`;
      a.click();
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
    window.implgenShare = {
      renderer: r,
      orbit,
      progressive,
      values,
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
