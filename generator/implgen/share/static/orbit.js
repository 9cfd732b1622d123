// implgen share: the orbit camera and its pointer controls, apart from any page (the viewer's convention:
// yaw about +y, pitch above the x-z plane, in degrees, at `distance` from `target`).
//
//   const orbit = new IgOrbit({yaw, pitch, distance, target, fov});
//   orbit.camera()                        // {eye, target, up, fov} for IgSurface.Renderer.setCamera
//   orbit.attach(canvas, onChange)        // drag turns, shift-drag (or two fingers) moves the target, the wheel
//                                         // (or a pinch) zooms, arrow keys turn, + and - zoom;
//                                         // onChange(moving): moving is false at rest
"use strict";

class IgOrbit {
  constructor({ yaw = 30, pitch = 25, distance = 6, target = [0, 0, 0], fov = 40 } = {}) {
    this.home = { yaw, pitch, distance, target: [...target], fov };
    this.reset();
  }

  reset() {
    Object.assign(this, JSON.parse(JSON.stringify(this.home)));
  }

  /** (right, up, back) unit vectors of the camera. */
  basis() {
    const y = (this.yaw * Math.PI) / 180;
    const p = (this.pitch * Math.PI) / 180;
    const back = [Math.cos(p) * Math.sin(y), Math.sin(p), Math.cos(p) * Math.cos(y)];
    const right = [Math.cos(y), 0, -Math.sin(y)];
    const up = [
      back[1] * right[2] - back[2] * right[1],
      back[2] * right[0] - back[0] * right[2],
      back[0] * right[1] - back[1] * right[0],
    ];
    return { right, up, back };
  }

  camera() {
    const { up, back } = this.basis();
    const eye = this.target.map((t, i) => t + this.distance * back[i]);
    return { eye, target: [...this.target], up, fov: this.fov };
  }

  turn(dx, dy) {
    this.yaw = (this.yaw - dx * 0.4) % 360;
    this.pitch = Math.max(-89, Math.min(89, this.pitch + dy * 0.4));
  }

  pan(dx, dy, heightPx) {
    const { right, up } = this.basis();
    const k = (this.distance * Math.tan((this.fov * Math.PI) / 360) * 2) / Math.max(1, heightPx);
    this.target = this.target.map((t, i) => t - k * dx * right[i] + k * dy * up[i]);
  }

  zoom(factor) {
    this.distance = Math.max(1e-3, Math.min(1e6, this.distance * factor));
  }

  attach(canvas, onChange) {
    const pointers = new Map(); // id -> {x, y}
    let restTimer = 0;
    const spread = () => {
      const [a, b] = [...pointers.values()];
      return Math.hypot(a.x - b.x, a.y - b.y);
    };
    const centre = () => {
      const ps = [...pointers.values()];
      return { x: ps.reduce((s, p) => s + p.x, 0) / ps.length, y: ps.reduce((s, p) => s + p.y, 0) / ps.length };
    };
    let last = null; // centre of the pointers at the last move
    let lastSpread = 0;
    canvas.addEventListener("pointerdown", (e) => {
      pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
      canvas.setPointerCapture(e.pointerId);
      last = centre();
      lastSpread = pointers.size === 2 ? spread() : 0;
      canvas.classList.add("dragging");
    });
    canvas.addEventListener("pointermove", (e) => {
      if (!pointers.has(e.pointerId)) return;
      pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
      const c = centre();
      const dx = c.x - last.x;
      const dy = c.y - last.y;
      last = c;
      if (pointers.size >= 2) {
        const s = spread();
        if (lastSpread > 0 && s > 0) this.zoom(lastSpread / s);
        lastSpread = s;
        this.pan(dx, dy, canvas.clientHeight);
      } else if (e.shiftKey) {
        this.pan(dx, dy, canvas.clientHeight);
      } else {
        this.turn(dx, dy);
      }
      onChange(true);
    });
    const up = (e) => {
      if (!pointers.delete(e.pointerId)) return;
      last = pointers.size ? centre() : null;
      lastSpread = pointers.size === 2 ? spread() : 0;
      if (pointers.size === 0) {
        canvas.classList.remove("dragging");
        onChange(false);
      }
    };
    canvas.addEventListener("pointerup", up);
    canvas.addEventListener("pointercancel", up);
    const rest = () => {
      clearTimeout(restTimer);
      restTimer = setTimeout(() => onChange(false), 180);
    };
    // the keyboard, once the canvas has the focus: an arrow turns as a 12.5-pixel drag that way (5 degrees), + and - zoom
    if (canvas.tabIndex < 0) canvas.tabIndex = 0;
    canvas.addEventListener("keydown", (e) => {
      const turns = { ArrowLeft: [-12.5, 0], ArrowRight: [12.5, 0], ArrowUp: [0, -12.5], ArrowDown: [0, 12.5] };
      if (Object.hasOwn(turns, e.key)) this.turn(...turns[e.key]);
      else if (e.key === "+" || e.key === "=") this.zoom(1 / 1.1);
      else if (e.key === "-") this.zoom(1.1);
      else return;
      e.preventDefault();
      onChange(true);
      rest();
    });
    canvas.addEventListener(
      "wheel",
      (e) => {
        e.preventDefault();
        this.zoom(Math.exp(Math.max(-200, Math.min(200, e.deltaY)) * 0.002));
        onChange(true);
        rest();
      },
      { passive: false },
    );
  }
}

if (typeof window !== "undefined") window.IgOrbit = IgOrbit;
