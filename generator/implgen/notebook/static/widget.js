// implgen.show: the widget's view (anywidget). Python puts share/static/surface.js and orbit.js before this
// file, so IgSurface and IgOrbit are the shared page's renderer and camera. "gpu": the shape's generated GLSL
// drawn here, orbit, zoom and a slider per param; "frames": the kernel's pictures (a scene, or a browser without
// WebGL2), the orbit and the sliders sent back to the kernel, which renders the next one.

function el_(tag, props = {}, style = {}) {
  const e = Object.assign(document.createElement(tag), props);
  Object.assign(e.style, style);
  return e;
}

function sliders(model, box, onInput, onChange) {
  const data = model.get("data");
  const values = [...model.get("values")];
  const inputs = (data.params || []).map((p, i) => {
    const row = el_("label", {}, { display: "flex", gap: "0.5em", alignItems: "center", font: "12px sans-serif" });
    const input = el_("input", { type: "range", min: p.min, max: p.max, step: (p.max - p.min) / 1000 });
    input.value = values[i];
    input.dataset.param = p.name;
    const shown = el_("span", { textContent: `${p.name} = ${values[i]}` }, { minWidth: "7em" });
    input.addEventListener("input", () => {
      values[i] = parseFloat(input.value);
      shown.textContent = `${p.name} = ${Number(values[i].toPrecision(6))}`;
      onInput(values);
    });
    input.addEventListener("change", () => onChange(values));
    row.append(shown, input);
    box.append(row);
    return { input, shown, name: p.name };
  });
  // values set from Python: the sliders follow
  model.on("change:values", () => {
    const now = model.get("values");
    inputs.forEach((s, i) => {
      values[i] = now[i];
      s.input.value = now[i];
      s.shown.textContent = `${s.name} = ${Number(now[i].toPrecision(6))}`;
    });
    onInput(values, true);
  });
  return values;
}

function gpuView(model, canvas, state) {
  const data = model.get("data");
  const r = new IgSurface.Renderer(canvas); // throws without WebGL2
  const log = r.setEquationProgram({
    name: data.glsl_name, shape: data.shape, runtime: data.runtime, header: data.header, params: data.params.length,
  });
  if (log) throw new Error(`the shader did not compile: ${log.split("\n")[0]}`);
  r.setMaterial(data.material);
  r.setClip(data.clip);
  r.setSize(model.get("width"), model.get("height"));
  const progressive = new IgSurface.Progressive(r, { onIdle: () => (state.drawn += 1) });
  state.renderer = r;
  state.progressive = progressive;
  return (values, orbit, moving) => {
    r.setParams(values);
    r.setCamera(orbit.camera());
    progressive.invalidate(moving);
  };
}

function framesView(model, img, state) {
  let url = "";
  const show = () => {
    const bytes = model.get("frame");
    if (!bytes || !bytes.byteLength) return;
    if (url) URL.revokeObjectURL(url);
    url = URL.createObjectURL(new Blob([bytes], { type: "image/png" }));
    img.onload = () => (state.drawn += 1);
    img.src = url;
  };
  model.on("change:frame", show);
  show();
  return () => {}; // the kernel draws: it hears of the change through the synced values and orbit
}

function render({ model, el }) {
  const [w, h] = [model.get("width"), model.get("height")];
  const root = el_("div", { className: "implgen-widget" }, { display: "inline-block" });
  const canvas = el_("canvas", { width: w, height: h }, { width: `${w}px`, height: `${h}px`, touchAction: "none" });
  const img = el_("img", { width: w, height: h, draggable: false }, { touchAction: "none" });
  const box = el_("div");
  const status = el_("div", {}, { font: "12px sans-serif", color: "#b00" });
  root.append(canvas, img, box, status);
  el.append(root);
  const state = { drawn: 0, mode: model.get("mode"), error: "" };
  root.implgen = state; // for tests and people poking at the page

  const orbit = new IgOrbit(model.get("orbit"));
  let draw = null;
  if (state.mode === "gpu") {
    try {
      draw = gpuView(model, canvas, state);
      model.set("webgl", "yes");
    } catch (err) {
      state.mode = "frames";
      status.textContent = `${err.message || err}: the kernel draws the pictures instead`;
      model.set("webgl", String(err.message || err));
    }
    model.save_changes();
  }
  if (state.mode === "frames") draw = framesView(model, img, state);
  (state.mode === "gpu" ? img : canvas).style.display = "none";
  const surface = state.mode === "gpu" ? canvas : img;

  const sync = (values) => {
    model.set("values", [...values]);
    const { yaw, pitch, distance, fov } = orbit;
    model.set("orbit", { yaw, pitch, distance, target: [...orbit.target], fov });
    model.save_changes();
  };
  const values = sliders(
    model, box,
    (v, fromKernel) => {
      if (state.mode === "gpu") draw(v, orbit, !fromKernel);
    },
    (v) => {
      if (state.mode === "gpu") draw(v, orbit, false);
      sync(v);
    },
  );
  // the orbit set from Python: the view follows (its own changes come back equal and are skipped)
  model.on("change:orbit", () => {
    const o = model.get("orbit");
    const same = ["yaw", "pitch", "distance", "fov"].every((k) => o[k] === orbit[k]);
    if (same && `${o.target}` === `${orbit.target}`) return;
    Object.assign(orbit, { yaw: o.yaw, pitch: o.pitch, distance: o.distance, fov: o.fov, target: [...o.target] });
    if (state.mode === "gpu") draw(values, orbit, false);
  });
  orbit.attach(surface, (moving) => {
    if (state.mode === "gpu") draw(values, orbit, moving);
    if (!moving) sync(values);
  });
  if (state.mode === "gpu") draw(values, orbit, false);
}

export default { render };
