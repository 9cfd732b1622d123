// implgen view: the share link. The page's whole view lives in its address after "#", in readable fields:
//   #v=1&eq=x^2+...&name=surface&params=a = 1&values=a:1.2&cam=yaw,pitch,distance,tx,ty,tz,fov
//     &clip=sphere:3[:cut]&color=f2bf4d&inside=5a8cf2&bg=1f1f24&lights=studio[&obj=2]
// (obj: with a scene file, the picked object, whose equation, name, params and values the link holds)
// A link is text from anywhere: decode() reads it as untrusted input, bounded in length, each field checked
// by its own pattern and range and dropped when it does not pass (the server checks everything again); it
// never evaluates anything. The numbers' ranges are the server's, sent in its hello (view/protocol.py RANGES,
// stated there once), so a link keeps no number the server would refuse. Plain JS, no build step.
"use strict";

window.implgenLink = (() => {
  const MAX_LINK = 16384; // characters after "#"
  const MAX_EQUATION = 8192;
  const MAX_PARAMS = 64;
  const NAME = /^[A-Za-z_][A-Za-z0-9_]{0,62}$/;
  const HEX = /^[0-9a-fA-F]{6}$/;
  const CLIPS = ["none", "sphere", "box"];
  const LIGHTS = ["studio", "headlight", "top", "scene"];
  const num = (s, lo, hi) => {
    if (typeof s !== "string" || !/^[-+0-9.eE]{1,32}$/.test(s)) return null;
    const x = Number(s);
    return Number.isFinite(x) && x >= lo && x <= hi ? x : null;
  };
  const hex = (rgb) => rgb.map((c) => Math.round(Math.max(0, Math.min(1, c)) * 255)
    .toString(16).padStart(2, "0")).join("");
  const rgb = (h) => [0, 2, 4].map((i) => parseInt(h.slice(i, i + 2), 16) / 255);
  const short = (x) => String(Number(x.toPrecision(12)));

  // the view -> the text after "#"
  function encode(view) {
    const o = view.orbit, op = view.options;
    const q = new URLSearchParams();
    q.set("v", "1");
    q.set("eq", view.equation);
    q.set("name", view.name);
    q.set("params", view.params);
    q.set("values", Object.entries(view.values).map(([k, v]) => `${k}:${short(v)}`).join(","));
    q.set("cam", [o.yaw, o.pitch, o.distance, ...o.target, o.fov].map(short).join(","));
    q.set("clip", op.clip === "none" ? "none" : `${op.clip}:${short(op.clip_size)}${op.cut ? ":cut" : ""}`);
    q.set("color", hex(op.color));
    q.set("inside", hex(op.inside));
    q.set("bg", hex(op.background));
    q.set("lights", op.lights);
    if (Number.isInteger(view.object)) q.set("obj", String(view.object));
    return q.toString();
  }

  // the text after "#" -> {view: the fields that passed, bad: the names of those that did not}; `ranges`: the
  // hello's limits.ranges, {value: [lo, hi], yaw: ..., ...}; a number without its range does not read
  function decode(fragment, ranges) {
    const within = (s, key) => {
      const r = ranges && Object.prototype.hasOwnProperty.call(ranges, key) ? ranges[key] : null;
      return Array.isArray(r) && r.length === 2 ? num(s, r[0], r[1]) : null;
    };
    const text = (fragment || "").replace(/^#/, "");
    const view = {}, bad = [];
    if (!text) return { view, bad };
    if (text.length > MAX_LINK) return { view, bad: ["the link (too long)"] };
    let q;
    try { q = new URLSearchParams(text); } catch (e) { return { view, bad: ["the link"] }; }
    if (q.get("v") !== "1") return { view, bad: ["the link (not a view link)"] };
    const eq = q.get("eq");
    if (eq !== null) { if (eq.length <= MAX_EQUATION && eq.trim()) view.equation = eq; else bad.push("eq"); }
    const name = q.get("name");
    if (name !== null) { if (NAME.test(name)) view.name = name; else bad.push("name"); }
    const params = q.get("params");
    if (params !== null) { if (params.length <= 4096) view.params = params; else bad.push("params"); }
    const values = q.get("values");
    if (values !== null) {
      const out = Object.create(null); // keyed by params' names: constructor or __proto__ is a name like any other
      const parts = values ? values.split(",") : [];
      for (const part of parts.slice(0, MAX_PARAMS)) {
        const [k, v] = part.split(":");
        const x = within(v, "value");
        if (NAME.test(k || "") && x !== null) out[k] = x; else bad.push(`values (${part.slice(0, 20)})`);
      }
      view.values = out;
    }
    const cam = q.get("cam");
    if (cam !== null) {
      const c = cam.split(",");
      const nums = ["yaw", "pitch", "distance", "target", "target", "target", "fov"].map((k, i) => within(c[i], k));
      if (c.length === 7 && nums.every((x) => x !== null)) {
        view.orbit = { yaw: nums[0], pitch: nums[1], distance: nums[2], target: nums.slice(3, 6), fov: nums[6] };
      } else bad.push("cam");
    }
    const options = {};
    const clip = q.get("clip");
    if (clip !== null) {
      const [kind, size, cut] = clip.split(":");
      const r = within(size, "clip_size");
      if (kind === "none") options.clip = "none";
      else if (CLIPS.includes(kind) && r !== null && (cut === undefined || cut === "cut")) {
        Object.assign(options, { clip: kind, clip_size: r, cut: cut === "cut" });
      } else bad.push("clip");
    }
    for (const [key, field] of [["color", "color"], ["inside", "inside"], ["bg", "background"]]) {
      const h = q.get(key);
      if (h !== null) { if (HEX.test(h)) options[field] = rgb(h); else bad.push(key); }
    }
    const lights = q.get("lights");
    if (lights !== null) { if (LIGHTS.includes(lights)) options.lights = lights; else bad.push("lights"); }
    if (Object.keys(options).length) view.options = options;
    const obj = q.get("obj");
    if (obj !== null) { if (/^[0-9]{1,5}$/.test(obj)) view.object = Number(obj); else bad.push("obj"); }
    return { view, bad };
  }

  return { encode, decode };
})();
