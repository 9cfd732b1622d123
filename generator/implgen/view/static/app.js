// implgen view: the page. Sends the view it wants over one WebSocket and draws the frames that come back.
// The server checks everything; this file only collects what the user set. Plain JS, no build step.
"use strict";

(() => {
  const $ = (id) => document.getElementById(id);
  const canvas = $("view");
  const ctx2d = canvas.getContext("2d");
  const HEADER = 12; // seq (u32), kind (u8), flags (u8), samples (u16: a KIND_MORE frame's), width (u16), height (u16)
  const KIND_COARSE = 0, KIND_FULL = 1, KIND_SAVE = 2, KIND_ONE = 3, KIND_MESH = 4, KIND_QUARTER = 5, KIND_MORE = 6;
  const KIND_FIX = 7; // a GPU-drawn scene's flagged pixels in double (gpu.js composites them)
  // a better frame of the same request wins: the refinement's half-size picture, 1 sample, more (their count in
  // the header's spare bytes), all samples
  const RANK = { [KIND_COARSE]: 0, [KIND_QUARTER]: 1, [KIND_ONE]: 2, [KIND_MORE]: 2, [KIND_FULL]: 1000 };
  const KIND_NAME = { [KIND_COARSE]: "coarse", [KIND_QUARTER]: "half size, 1 sample", [KIND_ONE]: "full, 1 sample",
    [KIND_FULL]: "full" };
  const KIND_MARK = { [KIND_COARSE]: "coarse", [KIND_QUARTER]: "quarter", [KIND_ONE]: "one", [KIND_MORE]: "more",
    [KIND_FULL]: "full" }; // the canvas's data-kind, for tests
  const FLAG_EMPTY = 1; // the frame shows nothing but the background
  // the GPU preview (gpu.js): draws the live picture in this browser where it can, else null or inactive
  // redraw: a scene's program has come; serverRest: too many flagged pixels at rest, the server's frame instead
  const gpu = window.ImplgenGpu ? ImplgenGpu.create({ stage: $("stage"), view: canvas, note: $("gpu-note"),
    toggle: $("gpu"), compare: $("compare"), status: $("status"), redraw: () => requestRender(true),
    serverRest: () => { serverRest = true; requestRender(true); } }) : null;
  let serverRest = false; // the next refined request is the server's whatever draws the live picture

  // Everything keyed by a param's name is a map without a prototype: a param may be called constructor,
  // toString or __proto__, and state.ranges[name] must not find Object.prototype's member instead.
  const byName = (obj) => {
    const out = Object.create(null);
    if (obj && typeof obj === "object") for (const [k, v] of Object.entries(obj)) out[k] = v;
    return out;
  };
  const state = {
    params: byName(), // name -> default (as the server parsed it)
    values: byName(), // name -> slider value
    ranges: byName(), // name -> [min, max], editable
    orbit: { yaw: 30, pitch: 25, distance: 6, target: [0, 0, 0], fov: 40 },
    options: {},
    home: null, // the orbit to go back to
  };
  const userRanges = new Set(); // the params whose slider span the user set by hand
  let ws = null;
  let lastError = ""; // the server's last error line, kept when the socket closes after it
  let messageIsError = false; // the message line holds an error: the next picture clears it
  let errorSeq = 0; // ... a picture of a request sent after the error came, not an older one still on its way
  const overlay = { connect: "connecting...", build: "", empty: false, unbounded: false }; // the overlay's words
  let lastBitmap = null; // the picture drawn last, drawn again when the canvas changes size
  let seq = 0;
  let drawnSeq = -1;
  let drawnKind = -1;
  let frames = 0;
  let queued = null; // {refine} of a render waiting for the next animation frame
  let restTimer = 0;
  let typing = 0; // the pause after typing that applies the equation
  const sentAt = new Map();

  // ---------------------------------------------------------------- colours
  const toHex = (rgb) => "#" + rgb.map((c) => Math.round(Math.max(0, Math.min(1, c)) * 255)
    .toString(16).padStart(2, "0")).join("");
  const fromHex = (hex) => [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255);

  // ---------------------------------------------------------------- what the page says
  // The message line lies over the top of the picture. `kind`: "error" (true) stays until a newer picture;
  // "note" (false: a file saved, a link copied) goes with the user's next action, or after NOTE_MS; "keep" (work
  // in progress, the connection lost) stays until something replaces it.
  const NOTE_MS = 8000;
  let messageKind = "";
  let noteTimer = 0;
  function showMessage(text, kind) {
    kind = kind === true ? "error" : kind === false || kind === undefined ? "note" : kind;
    const line = $("message");
    line.textContent = text;
    line.classList.toggle("bad", kind === "error");
    messageKind = text ? kind : "";
    messageIsError = kind === "error" && text !== "";
    if (kind === "error") { lastError = text; errorSeq = seq; }
    clearTimeout(noteTimer);
    if (messageKind === "note") noteTimer = setTimeout(() => showMessage("", "note"), NOTE_MS);
  }

  // the user did something new: a note on what was done before (a link copied, a file saved) is stale
  function acted() {
    if (messageKind === "note") showMessage("", "note");
  }

  function showOverlay() {
    // the most pressing first: a build in progress, the connection, an empty picture, a surface without a clip
    // that runs on without end (it may fill the view with one colour)
    const endless = overlay.unbounded && !sceneMode && $("clip").value === "none"
      ? "this surface runs on without end: with clip none it can fill the view; choose a sphere or box clip" : "";
    $("overlay").textContent = overlay.build || overlay.connect || (overlay.empty ? "no real points in view" : "")
      || endless;
  }

  function showEmpty(empty) {
    overlay.empty = empty;
    showOverlay();
  }

  // ---------------------------------------------------------------- messages out
  function send(msg) {
    if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(msg));
  }

  let goodClipSize = null; // the clip size of the last picture drawn: used while the field holds no number
  function readOptions() {
    const field = $("clip-size");
    const size = Number(field.value);
    const ok = field.value.trim() !== "" && Number.isFinite(size) && size > 0;
    field.classList.toggle("bad", !ok);
    if (!ok) showMessage("clip size: expected a positive number", true);
    return {
      clip: $("clip").value,
      clip_size: ok ? size : (goodClipSize ?? state.options.clip_size),
      cut: $("cut").checked,
      color: fromHex($("color").value),
      inside: fromHex($("inside").value),
      lights: $("lights").value,
      background: fromHex($("background").value),
    };
  }

  // A render request goes out at most once per animation frame; the newest view is what is sent. With the GPU
  // preview, the page draws the live picture itself and asks the server for the refined frame only.
  function requestRender(refine) {
    if (queued) { queued.refine = queued.refine || refine; return; }
    queued = { refine };
    requestAnimationFrame(() => {
      const q = queued;
      queued = null;
      seq += 1;
      if (holdNext && q.refine) { holdSeq = seq; holdNext = false; }
      state.options = readOptions();
      if (q.refine) keepLink();
      sentAt.set(seq, { t: performance.now(), clip: state.options.clip_size });
      const view = { orbit: state.orbit, values: state.values, options: state.options };
      const onGpu = gpu !== null && !(q.refine && serverRest) && gpu.draw(view, !q.refine, seq);
      if (q.refine) serverRest = false;
      if (onGpu) { drawnSeq = seq; drawnKind = -1; } // older server frames are stale; this request's are not
      // a scene the GPU draws keeps its picture at rest: the server fixes its flagged pixels (gpu.js), no frame
      const refine = q.refine && !(onGpu && gpu.fixesRest());
      send({
        type: "render", seq, refine, width: canvas.width, height: canvas.height,
        values: state.values, orbit: state.orbit, options: state.options, gpu: onGpu,
      });
    });
  }

  // The address carries the view (share.js): kept up to date whenever the view rests.
  function keepLink() {
    if (acceptedEquation === null) return;
    const text = implgenLink.encode({
      equation: acceptedEquation, name: $("shape-name").value, params: $("params-text").value,
      values: state.values, orbit: state.orbit, options: state.options,
      object: sceneMode ? Number($("object").value) : undefined, // a scene's: the picked object's edits
    });
    history.replaceState(null, "", `${location.pathname}${location.search}#${text}`);
  }

  // A share link's view, applied once the page has its first state from the server: its equation is sent as a
  // new shape (its clip is the user's own: not fitted), its slider values wait for the shape's reply.
  let linkValues = null;
  let linkObject = null; // a scene link's object: its equation is sent for that object
  let linkClip = null; // ... and its clip, given to it once its shape is back (when it can take one)
  let linkRanges = null; // the server's ranges of the view's numbers (the hello): a link's are read within them
  function openLink() {
    const { view, bad } = implgenLink.decode(location.hash, linkRanges);
    // a note, not an error: the picture that follows does not clear it
    if (bad.length) showMessage(`share link: left out what did not read: ${bad.join(", ")}`, false);
    if (view.orbit) { state.orbit = view.orbit; linkCamera = true; }
    if (view.options) {
      setOptions(Object.assign(readOptions(), view.options));
      if (view.options.clip !== undefined) userClip = true; // the link's clip (and camera) stay as they are
      if (view.options.clip_size !== undefined) goodClipSize = view.options.clip_size;
    }
    linkObject = sceneMode && view.object !== undefined ? view.object : null;
    linkClip = sceneMode && view.options && view.options.clip !== undefined ? readOptions() : null;
    if (view.equation === undefined) {
      if (linkObject !== null) { send({ type: "object", index: linkObject }); linkObject = null; }
      return false;
    }
    $("equation").value = view.equation;
    if (view.params !== undefined) $("params-text").value = view.params;
    if (view.name !== undefined) { $("shape-name").value = view.name; userName = true; }
    linkValues = view.values || null;
    applyShape();
    return true;
  }

  // Coarse frames while something moves; refined once it has rested (a drag: once the pointer stops, held or not).
  const REST = 180, DRAG_REST = 100; // ms
  function movedFor(rest) {
    requestRender(false);
    clearTimeout(restTimer);
    restTimer = setTimeout(() => requestRender(true), rest);
  }
  function moved() { movedFor(REST); } // (an event listener too: it takes no argument)

  function parseParamsText(text) {
    const out = byName();
    for (const part of text.split(",")) {
      if (!part.trim()) continue;
      const [name, value] = part.split("=").map((s) => s.trim());
      out[name] = value === undefined ? "" : value; // the server checks names and numbers
    }
    return out;
  }

  // The clip size is fitted to each new equation's real points until the user sets it.
  let userClip = false;
  const DEFAULT_CLIP = 3;
  // A typed equation's shape is called "surface" unless the user names it; the same equation keeps its name.
  let userName = false;
  let sceneMode = false; // a scene file: the equation box edits one of its shapes, picked in the picture or a list
  function showObjects(list, index) {
    const select = $("object");
    select.replaceChildren(...list.map((o) => Object.assign(document.createElement("option"),
      { value: o.index, textContent: `${o.name} (${o.where})` })));
    select.value = index;
  }
  let acceptedEquation = null; // the equation text the server last accepted (as the box showed it)
  function applyShape() {
    clearTimeout(typing);
    acted();
    const text = $("equation").value;
    const name = userName ? $("shape-name").value.trim()
      : (text === acceptedEquation || sceneMode ? $("shape-name").value : "surface");
    sentEquation = text;
    const object = linkObject !== null ? { object: linkObject } : {};
    linkObject = null;
    send({ type: "shape", equation: text, name, params: parseParamsText($("params-text").value),
      fit: !userClip, ...object });
  }

  function fitClip(size) {
    if (userClip) return;
    const r = size ?? DEFAULT_CLIP; // none: the surface runs on (or has no real point): the default ball
    $("clip-size").value = r;
    $("clip-size").classList.remove("bad");
    goodClipSize = r;
  }

  // The camera frames the clip at the start, for each new equation and on Reset: the clip's bounding ball (about
  // the origin; a box's is sqrt(3) times its half-edge) whole in the picture's narrower direction, with a margin,
  // whether the size was fitted or set by hand. A link's or a saved file's camera is kept.
  let linkCamera = false; // a link gave the camera: its shape keeps it
  function frameClip() {
    const o = state.orbit;
    const typed = Number($("clip-size").value);
    const size = typed > 0 ? typed : (goodClipSize ?? DEFAULT_CLIP);
    const r = $("clip").value === "box" ? size * Math.sqrt(3) : size;
    const aspect = canvas.clientWidth > 0 && canvas.clientHeight > 0 ? canvas.clientWidth / canvas.clientHeight : 1;
    const half = Math.atan(Math.tan(o.fov * Math.PI / 360) * Math.min(1, aspect));
    o.target = [0, 0, 0];
    o.distance = Math.min(1e6, r / Math.sin(half) * 1.1);
  }

  // The parser's line under the equation box; where it knows the character at fault, that line of the equation
  // (at most CARET_WIDE characters of it about the place) with a caret under it.
  const CARET_WIDE = 34;
  let sentEquation = ""; // the equation text last sent: an error's position is in it
  function showEquationError(message, position) {
    const box = $("equation-error");
    box.replaceChildren(document.createTextNode(message));
    const text = sentEquation;
    if (!Number.isInteger(position) || position < 0 || position > text.length) return;
    const start = text.lastIndexOf("\n", position - 1) + 1;
    const stop = text.indexOf("\n", position);
    let line = text.slice(start, stop < 0 ? text.length : stop).replace(/\t/g, " ");
    let column = position - start;
    if (line.length > CARET_WIDE) {
      const from = Math.max(0, Math.min(column - CARET_WIDE / 2, line.length - CARET_WIDE));
      line = (from > 0 ? "\u2026" : "") + line.slice(from, from + CARET_WIDE) + (from + CARET_WIDE < line.length ? "\u2026" : "");
      column += from > 0 ? 1 - from : 0;
    }
    const caret = Object.assign(document.createElement("pre"), { className: "caret" });
    caret.textContent = `${line}\n${" ".repeat(column)}^`;
    box.append(caret);
  }

  // A scene's picked object: its clip in the Look controls, which give it one when it is a top-level object (in
  // CSG the other parts bound it); the cut solid and the colours stay the file's.
  function showObjectClip(msg) {
    const c = sceneMode ? msg.object_clip : null;
    if (!c) return;
    $("clip").value = c.clip;
    $("clip-size").value = c.size;
    $("clip-size").classList.remove("bad");
    goodClipSize = c.size;
    for (const id of ["clip", "clip-size"]) $(id).disabled = !c.clippable;
  }
  function sendObjectClip() {
    const size = Number($("clip-size").value);
    if (!(size > 0)) return; // readOptions says so
    send({ type: "clip", clip: $("clip").value, size });
    if (endlessWarned) { endlessWarned = false; showMessage("", "note"); }
  }
  // a typed equation that runs on without end, in an object with no clip, can cover the whole picture
  let endlessWarned = false;
  function warnEndless(msg) {
    const c = msg.object_clip;
    if (!msg.unbounded || !c || c.clip !== "none" || !c.clippable) return;
    showMessage(`${msg.name} runs on without end and has no clip: it can cover the picture. Give it a clip `
      + "(Look: clip and size) to show the part inside a ball or a box.", "keep");
    endlessWarned = true;
  }

  // ---------------------------------------------------------------- messages in
  function showShape(msg) {
    $("equation").classList.remove("bad");
    $("equation-error").textContent = "";
    state.params = byName(msg.params);
    state.values = byName(msg.values);
    const given = byName(msg.ranges);
    for (const [k, v] of Object.entries(state.params)) {
      const r = given[k];
      if (!userRanges.has(k) && Array.isArray(r) && r.length === 2) {
        state.ranges[k] = [Math.min(r[0], state.values[k]), Math.max(r[1], state.values[k])];
      } else if (!Object.hasOwn(state.ranges, k)) {
        const span = Math.max(1, Math.abs(v));
        state.ranges[k] = [v - span, v + span];
      }
    }
    $("params-text").value = Object.entries(state.params).map(([k, v]) => `${k} = ${v}`).join(", ");
    $("shape-name").value = msg.name;
    acceptedEquation = $("equation").value;
    $("degree").textContent = `degree ${msg.degree}`;
    buildSliders();
  }

  // a slider moves in decimal steps, a thousandth of its span or finer (0.5 is a value it can take)
  const sliderStep = (lo, hi) => 10 ** (Math.floor(Math.log10(hi - lo)) - 3);

  function buildSliders() {
    const box = $("sliders");
    box.replaceChildren();
    for (const name of Object.keys(state.params)) {
      const [lo, hi] = state.ranges[name];
      const row = document.createElement("div");
      row.className = "slider";
      const label = document.createElement("span");
      label.textContent = name;
      const value = document.createElement("span");
      value.className = "value";
      const range = document.createElement("div");
      range.className = "range";
      const min = Object.assign(document.createElement("input"), { type: "number", value: lo, step: "any" });
      const max = Object.assign(document.createElement("input"), { type: "number", value: hi, step: "any" });
      const slider = Object.assign(document.createElement("input"), {
        type: "range", min: lo, max: hi, step: sliderStep(lo, hi), value: state.values[name],
      });
      slider.dataset.name = name;
      slider.setAttribute("aria-label", name);
      min.setAttribute("aria-label", `${name} min`);
      max.setAttribute("aria-label", `${name} max`);
      const show = () => { value.textContent = Number(state.values[name]).toPrecision(4); };
      show();
      // coarse while it moves, refined when it rests: even when it is let go where it started (no "change")
      slider.addEventListener("input", () => { acted(); state.values[name] = parseFloat(slider.value); show(); moved(); });
      slider.addEventListener("change", () => requestRender(true));
      const setRange = () => {
        const a = parseFloat(min.value), b = parseFloat(max.value);
        if (Number.isFinite(a) && Number.isFinite(b) && a < b) {
          state.ranges[name] = [a, b];
          userRanges.add(name); // the user's own span stays while the param does
          slider.min = a; slider.max = b; slider.step = sliderStep(a, b);
          slider.value = state.values[name];
        }
      };
      min.addEventListener("change", setRange);
      max.addEventListener("change", setRange);
      range.append(min, slider, max);
      row.append(label, value, range);
      box.append(row);
    }
  }

  function setOptions(o) {
    state.options = o;
    $("clip").value = o.clip;
    $("clip-size").value = o.clip_size;
    $("cut").checked = o.cut;
    $("color").value = toHex(o.color);
    $("inside").value = toHex(o.inside);
    $("background").value = toHex(o.background);
    $("lights").value = o.lights;
  }

  // A new shape's first request (no drag) holds its coarse frame up to HOLD_MS for the full-size one behind it:
  // the first picture after a gallery pick was an 84 x 71 blur. A drag's frames are never held.
  const HOLD_MS = 1500;
  let holdNext = false, holdSeq = -1, held = null;
  async function drawFrame(buf, released = false) {
    const view = new DataView(buf);
    const fseq = view.getUint32(0), kind = view.getUint8(4), flags = view.getUint8(5);
    if (kind === KIND_COARSE && fseq === holdSeq && !released) {
      held = buf;
      setTimeout(() => { if (held === buf) { held = null; drawFrame(buf, true); } }, HOLD_MS);
      return;
    }
    if (kind !== KIND_COARSE && fseq >= holdSeq) held = null; // the sharp one came: the held one is stale
    const samples = view.getUint16(6), w = view.getUint16(8), h = view.getUint16(10);
    const bytes = new Uint8Array(buf, HEADER);
    lastError = "";
    if (kind === KIND_MESH) { implgenMesh.received(bytes); return; } // Save mesh (mesh.js)
    if (kind === KIND_FIX) { if (gpu) gpu.fixed(fseq, samples, w, h, bytes); return; } // samples: the part
    if (kind === KIND_SAVE) {
      const name = `${fileName()}.png`;
      download(new Blob([bytes], { type: "image/png" }), name);
      showMessage(`saved ${name}: ${w} \u00d7 ${h} pixels`, "note");
      return;
    }
    if (RANK[kind] === undefined) return;
    const rank = RANK[kind] + (kind === KIND_MORE ? samples : 0);
    const stale = () => fseq < drawnSeq || (fseq === drawnSeq && rank <= drawnKind);
    if (stale()) return;
    const type = kind === KIND_COARSE ? "image/jpeg" : "image/png";
    const bitmap = await createImageBitmap(new Blob([bytes], { type }));
    if (stale()) return;
    ctx2d.imageSmoothingEnabled = true;
    ctx2d.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
    lastBitmap = bitmap;
    drawnSeq = fseq; drawnKind = rank; frames += 1;
    canvas.dataset.seq = fseq; canvas.dataset.kind = KIND_MARK[kind];
    canvas.dataset.frames = frames;
    const sent = sentAt.get(fseq);
    const ms = sent === undefined ? "" : ` ${Math.round(performance.now() - sent.t)} ms`;
    if (sent !== undefined && !$("clip-size").classList.contains("bad")) goodClipSize = sent.clip;
    // a picture drawn: the last error is over (not a field's own complaint while it still holds no number)
    if (messageIsError && fseq > errorSeq && !$("clip-size").classList.contains("bad")) showMessage("", false);
    const name = kind === KIND_MORE ? `full, ${samples} samples` : KIND_NAME[kind];
    $("status").textContent = `${name} ${w} x ${h}${ms}`;
    if (gpu && kind !== KIND_COARSE && kind !== KIND_QUARTER) gpu.serverFrame(ctx2d, kind === KIND_FULL);
    showEmpty((flags & FLAG_EMPTY) !== 0);
    for (const k of sentAt.keys()) if (k < fseq) sentAt.delete(k);
  }

  // saved files are named after the shape, or in a scene after the scene file (they hold the whole scene)
  let sceneName = "";
  function fileName() {
    const name = sceneMode ? sceneName : $("shape-name").value;
    return String(name).replace(/[^A-Za-z0-9_-]/g, "") || "surface";
  }

  function download(blob, name) {
    const a = Object.assign(document.createElement("a"), { href: URL.createObjectURL(blob), download: name });
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  }

  function onMessage(ev) {
    if (ev.data instanceof ArrayBuffer) { drawFrame(ev.data); return; }
    const msg = JSON.parse(ev.data);
    if (msg.type === "hello" || msg.type === "shape") { // name -> default, name -> value
      msg.params = byName(msg.params);
      msg.values = byName(msg.values);
    }
    if (msg.type === "hello") {
      overlay.connect = "";
      showOverlay();
      $("equation").value = msg.equation;
      state.orbit = msg.orbit;
      state.home = JSON.parse(JSON.stringify(msg.orbit));
      maxFrame = msg.limits.frame;
      linkRanges = msg.limits.ranges;
      fitCanvas();
      setOptions(msg.options);
      if (msg.frame) { frameClip(); state.home = JSON.parse(JSON.stringify(state.orbit)); }
      sceneMode = msg.mode === "scene";
      sceneName = typeof msg.scene_name === "string" ? msg.scene_name : "scene";
      $("gallery-row").hidden = sceneMode || gallery.length === 0;
      $("object-row").hidden = !sceneMode;
      if (sceneMode) showObjects(msg.objects, msg.object);
      if (msg.mode !== "scene") $("lights").querySelector("option[value=scene]").disabled = true;
      else for (const id of ["cut", "color", "inside"]) $(id).disabled = true; // the file's own
      showObjectClip(msg);
      showShape(msg);
      if (gpu) gpu.hello(msg, send);
      if (!openLink()) requestRender(true); // with a link's equation: drawn once it is built
    } else if (msg.type === "shape") {
      if (linkValues) { // the link's slider values, for the params the shape has
        for (const [k, v] of Object.entries(linkValues)) {
          if (Object.hasOwn(msg.values, k)) msg.values[k] = v; // its slider's span widened to hold it
        }
        linkValues = null;
      }
      if (msg.object !== undefined) { // another object of the scene picked: its equation in the box
        $("equation").value = msg.equation;
        userName = false;
        $("equation").classList.remove("bad");
      }
      if (sceneMode && msg.objects) showObjects(msg.objects, msg.object ?? Number($("object").value));
      const fresh = !sceneMode && $("equation").value !== acceptedEquation; // a new equation, not new defaults
      showShape(msg);
      if (gpu) gpu.shape(msg);
      if ("fit" in msg) fitClip(msg.fit);
      showObjectClip(msg);
      if (linkClip && msg.object_clip && msg.object_clip.clippable) {
        $("clip").value = linkClip.clip;
        $("clip-size").value = linkClip.clip_size;
        sendObjectClip();
      }
      linkClip = null;
      if (sceneMode) warnEndless(msg);
      overlay.unbounded = msg.unbounded === true;
      showOverlay();
      if (fresh && !linkCamera) frameClip();
      if (fresh) holdNext = true; // its first picture: not a blur of a few pixels when a sharp one is near
      linkCamera = false;
      requestRender(true);
    } else if (msg.type === "glsl") {
      if (gpu) gpu.program(msg);
    } else if (msg.type === "status") {
      overlay.build = msg.text;
      showOverlay();
    } else if (msg.type === "error") {
      if (msg.field === "equation") {
        $("equation").classList.add("bad");
        showEquationError(msg.message, msg.position);
      } else {
        showMessage(msg.message, true);
      }
    } else if (msg.type === "mesh") {
      implgenMesh.message(msg);
    } else if (msg.type === "yaml") {
      const name = `${fileName()}.yaml`;
      download(new Blob([msg.text], { type: "application/yaml" }), name);
      showMessage(`saved ${name}: the view as a scene file (implgen render draws it, implgen view reopens it)`, "note");
    } else if (msg.type === "page") {
      download(new Blob([msg.text], { type: "text/html" }), msg.name);
      const cut = typeof msg.note === "string" ? `; ${msg.note}` : ""; // its shader cut by the GLSL budget
      showMessage(`saved ${msg.name}: this view as a page that draws it with WebGL2, no server needed${cut}`, "note");
    } else if (msg.type === "c") {
      $("code").textContent = msg.text;
      $("code-dialog").showModal();
    }
  }

  function connect() {
    const proto = location.protocol === "https:" ? "wss" : "ws";
    // a server listening beyond this machine gave its link a token: the socket asks for it too
    const token = new URLSearchParams(location.search).get("token");
    const query = token ? `?token=${encodeURIComponent(token)}` : "";
    ws = new WebSocket(`${proto}://${location.host}/ws${query}`);
    ws.binaryType = "arraybuffer";
    ws.addEventListener("message", onMessage);
    ws.addEventListener("close", (e) => {
      implgenMesh.reset(); // Save mesh (mesh.js)
      const why = e.reason ? `: ${e.reason}` : " (reload to reconnect)";
      // the error the server closed after stays in view (a scene file that no longer reads, too many pages)
      const text = e.code === 1013 && lastError ? lastError
        : `${lastError ? lastError + " - " : ""}disconnected from the server${why}`;
      showMessage(text, "keep");
      overlay.connect = e.code === 1013 ? "too many pages open" : "disconnected";
      showOverlay();
    });
  }

  // ---------------------------------------------------------------- the picture: orbit, pan, zoom
  let drag = null;
  canvas.addEventListener("pointerdown", (e) => {
    acted();
    drag = { x: e.clientX, y: e.clientY, pan: e.shiftKey, x0: e.clientX, y0: e.clientY, moved: false };
    canvas.setPointerCapture(e.pointerId);
    canvas.classList.add("dragging");
  });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX; drag.y = e.clientY;
    if (!drag.moved && Math.hypot(e.clientX - drag.x0, e.clientY - drag.y0) < 4) return; // a click, so far
    drag.moved = true;
    const o = state.orbit;
    if (drag.pan || e.shiftKey) {
      const y = o.yaw * Math.PI / 180, p = o.pitch * Math.PI / 180;
      const right = [Math.cos(y), 0, -Math.sin(y)];
      const back = [Math.cos(p) * Math.sin(y), Math.sin(p), Math.cos(p) * Math.cos(y)];
      const up = [back[1] * right[2] - back[2] * right[1], back[2] * right[0] - back[0] * right[2],
        back[0] * right[1] - back[1] * right[0]];
      const k = o.distance * Math.tan(o.fov * Math.PI / 360) * 2 / canvas.clientHeight;
      o.target = o.target.map((t, i) => t - k * dx * right[i] + k * dy * up[i]);
    } else {
      o.yaw = (o.yaw - dx * 0.4) % 360;
      o.pitch = Math.max(-89, Math.min(89, o.pitch + dy * 0.4));
    }
    // the GPU draws a held view itself: the server refines it once the button is released
    if (gpu !== null && gpu.active()) { clearTimeout(restTimer); requestRender(false); } else movedFor(DRAG_REST);
  });
  const endDrag = (e) => {
    if (!drag) return;
    const click = !drag.moved;
    drag = null;
    canvas.classList.remove("dragging");
    if (!click) { clearTimeout(restTimer); requestRender(true); return; }
    if (sceneMode && e.type === "pointerup") { // a click on a scene: edit the object there
      const r = canvas.getBoundingClientRect();
      const x = (e.clientX - r.left) * canvas.width / r.width, y = (e.clientY - r.top) * canvas.height / r.height;
      send({ type: "pick", x: Math.max(0, Math.min(canvas.width - 1, x)),
        y: Math.max(0, Math.min(canvas.height - 1, y)), width: canvas.width, height: canvas.height });
    }
  };
  canvas.addEventListener("pointerup", endDrag);
  canvas.addEventListener("pointercancel", endDrag);
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    acted();
    state.orbit.distance = Math.max(1e-3, Math.min(1e6, state.orbit.distance * Math.exp(e.deltaY * 0.001)));
    moved();
  }, { passive: false });

  // ---------------------------------------------------------------- controls
  $("equation").addEventListener("keydown", (e) => {
    if (e.key === "Enter" && !e.shiftKey) { e.preventDefault(); applyShape(); }
  });
  $("equation").addEventListener("input", () => { clearTimeout(typing); typing = setTimeout(applyShape, 600); });
  $("params-text").addEventListener("keydown", (e) => { if (e.key === "Enter") applyShape(); });
  $("apply").addEventListener("click", applyShape);
  $("clip-size").addEventListener("input", () => { userClip = true; });
  for (const id of ["clip", "clip-size", "cut", "color", "inside", "background", "lights"]) {
    $(id).addEventListener("input", () => {
      acted();
      if (sceneMode && (id === "clip" || id === "clip-size")) sendObjectClip(); // the picked object's own
      moved();
      showOverlay();
    });
    $(id).addEventListener("change", () => requestRender(true));
  }
  $("reset-view").addEventListener("click", () => {
    acted();
    state.orbit = JSON.parse(JSON.stringify(state.home));
    if (!sceneMode) frameClip(); // the clip as it is now
    requestRender(true);
  });
  $("save-png").addEventListener("click", () => {
    acted();
    showMessage(`rendering ${$("save-width").value} \u00d7 ${$("save-height").value} pixels...`, "keep");
    lastError = "";
    send({ type: "save_png", width: parseInt($("save-width").value, 10), height: parseInt($("save-height").value, 10),
      spp: parseInt($("save-spp").value, 10) });
  });
  // a link pasted into this page's address (only the part after "#" differs: no reload) opens its view too
  window.addEventListener("hashchange", () => { if (ws && !openLink()) requestRender(true); });
  $("object").addEventListener("change", () => { acted(); send({ type: "object", index: Number($("object").value) }); });

  // ---------------------------------------------------------------- the gallery (gallery.json: docs/surfaces.md)
  let gallery = [];
  function showGallery(list) {
    gallery = Array.isArray(list) ? list : [];
    $("gallery-row").hidden = sceneMode || gallery.length === 0;
    $("gallery").append(...gallery.map((g, i) => Object.assign(document.createElement("option"),
      { value: String(i), textContent: String(g.title) })));
  }
  fetch("/gallery.json").then((r) => (r.ok ? r.json() : [])).then(showGallery).catch(() => showGallery([]));
  $("gallery").addEventListener("change", () => {
    const g = gallery[Number($("gallery").value)];
    $("gallery").value = "";
    if (!g) return;
    acted();
    const params = g.params || {};
    $("equation").value = g.equation;
    $("params-text").value = Object.entries(params).map(([k, v]) => `${k} = ${v}`).join(", ");
    state.ranges = byName(g.ranges);
    userRanges.clear();
    $("gallery-note").textContent = `${g.title}: ${g.description} (${g.reference})`;
    userName = false;
    sentEquation = g.equation;
    send({ type: "shape", equation: g.equation, name: g.name, params, ranges: g.ranges || {}, bounds: g.bounds || null,
      fit: !userClip });
  });
  $("copy-link").addEventListener("click", () => {
    keepLink();
    // with a scene file: the link names the file's page, and holds the camera and the picked object's edits
    const what = sceneMode ? "this scene's view: the camera, the picked object and its edits (not other objects' "
      + "edits; the scene file is the server's)" : "this view";
    navigator.clipboard.writeText(location.href).then(() => showMessage(`link copied: it reopens ${what}`, false),
      () => showMessage(`the link (it reopens ${what}): ${location.href}`, false));
  });
  const pageRanges = () => {
    const ranges = byName();
    for (const k of Object.keys(state.params)) ranges[k] = state.ranges[k];
    return ranges;
  };
  $("save-yaml").addEventListener("click", () => {
    acted();
    send({ type: "save_yaml", width: canvas.width, height: canvas.height, ranges: pageRanges() });
  });
  $("shape-name").addEventListener("input", () => { userName = true; });
  $("shape-name").addEventListener("keydown", (e) => { if (e.key === "Enter") applyShape(); });
  $("show-c").addEventListener("click", () => send({ type: "show_c" }));
  $("export-page").addEventListener("click", () => {
    showMessage("making the page (its GLSL)...", "keep");
    send({ type: "export_page", ranges: pageRanges() }); // the sliders' spans as the page shows them
  });
  $("message").addEventListener("click", () => showMessage("", "note")); // dismissed
  $("close-code").addEventListener("click", () => $("code-dialog").close());

  // ---------------------------------------------------------------- the picture's size: the window's
  // The canvas holds as many pixels as the screen shows (CSS size x devicePixelRatio: sharp on high-DPI
  // screens), at most the server's largest frame; a new size is drawn refined once the resizing rests.
  let maxFrame = [2048, 2048];
  function fitCanvas() {
    const stage = $("stage");
    const dpr = window.devicePixelRatio || 1;
    let w = Math.round(stage.clientWidth * dpr), h = Math.round(stage.clientHeight * dpr);
    const k = Math.min(1, maxFrame[0] / w, maxFrame[1] / h);
    w = Math.max(16, Math.floor(w * k)); h = Math.max(16, Math.floor(h * k));
    if (w === canvas.width && h === canvas.height) return false;
    canvas.width = w; canvas.height = h;
    if (lastBitmap) ctx2d.drawImage(lastBitmap, 0, 0, w, h);
    return true;
  }
  let resizeTimer = 0;
  new ResizeObserver(() => {
    if (!fitCanvas() || !ws || ws.readyState !== WebSocket.OPEN || drawnSeq < 0) return;
    requestRender(false);
    clearTimeout(resizeTimer);
    resizeTimer = setTimeout(() => requestRender(true), 180);
  }).observe($("stage"));
  fitCanvas();

  const fullScreen = () => {
    if (document.fullscreenElement) document.exitFullscreen();
    else $("stage").requestFullscreen().catch(() => {});
  };
  $("fullscreen").addEventListener("click", fullScreen);
  document.addEventListener("keydown", (e) => {
    if (e.key === "f" && e.target === document.body) fullScreen();
  });

  // the page's state, for tests and for the share link: a copy, never the live object
  window.implgenState = () => JSON.parse(JSON.stringify({ orbit: state.orbit, options: readOptions(),
    values: state.values }));

  implgenMesh.attach({ send, showMessage, download }); // Save mesh (mesh.js)
  connect();
})();
