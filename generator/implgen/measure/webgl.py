"""GLSL in a real browser: headless Chromium's WebGL2, driven by Selenium, for the GLSL tests and
bench/glsl_compare.py.

Headless Chromium gives WebGL2 through ANGLE on SwiftShader, a CPU emulation of a GPU: the pixels are what a
GPU's float arithmetic gives, the frame times are not a GPU's. The flags (FLAGS) ask for SwiftShader
explicitly, so the same renderer is used with or without a GPU on the machine.

`WebGL.run(fragment, size, uniforms, origins, dirs)` runs a fragment shader once per ray: origin and direction
come in as RGBA32F textures (xyz, and w = tmin for the origin, tmax for the direction), the shader writes an
RGBA32F pixel, and the pixels come back as a float32 array, tile by tile (a long draw is split into bands of
rows, each finished and read before the next, so no single draw runs long enough for a watchdog). The harness
page compiles and draws with the renderer's own code (share/static/surface.js: `IgSurface.compileProgram`,
`IgSurface.fullScreenTriangle`, the one vertex shader), run before the harness's script.
"""

from __future__ import annotations

import base64
import shutil

import numpy as np

from implgen.resources import surface_js

FLAGS = (
    "--headless=new",
    "--no-sandbox",
    "--disable-dev-shm-usage",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--window-size=800,600",
)

# After surface.js (the shared page's and the viewer's renderer, whose compile step and full-screen triangle it
# uses: one copy of that code): a canvas whose shader runs once per ray of a texture.
_HARNESS = r"""
const canvas = document.createElement('canvas');
document.body.appendChild(canvas);
const gl = canvas.getContext('webgl2', {antialias: false, preserveDrawingBuffer: true});
if (!gl) { window.ig = {error: 'no WebGL2'}; return 'no WebGL2'; }
if (!gl.getExtension('EXT_color_buffer_float')) { window.ig = {error: 'no EXT_color_buffer_float'}; return 'no float'; }
const vbo = IgSurface.fullScreenTriangle(gl);
function b64floats(s) {
  const bin = atob(s); const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
  return new Float32Array(bytes.buffer);
}
function floatsb64(f) {
  const bytes = new Uint8Array(f.buffer); let s = '';
  for (let i = 0; i < bytes.length; i += 32768) s += String.fromCharCode.apply(null, bytes.subarray(i, i + 32768));
  return btoa(s);
}
function texture(unit, w, h, data) {
  const t = gl.createTexture();
  gl.activeTexture(gl.TEXTURE0 + unit);
  gl.bindTexture(gl.TEXTURE_2D, t);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, w, h, 0, gl.RGBA, gl.FLOAT, data);
  for (const k of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, k, gl.NEAREST);
  return t;
}
window.ig = {
  info() {
    const e = gl.getExtension('WEBGL_debug_renderer_info');
    return [gl.getParameter(gl.VERSION), e ? gl.getParameter(e.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER)];
  },
  compile(fsrc) {
    try {
      const prog = IgSurface.compileProgram(gl, fsrc);
      if (this.prog) gl.deleteProgram(this.prog);
      this.prog = prog;
      return '';
    } catch (err) { return String(err.message || err) || 'compile failed'; }
  },
  setup(w, h, orig, dir, uniforms) {
    this.w = w; this.h = h;
    canvas.width = w; canvas.height = h;
    gl.useProgram(this.prog);
    for (const t of this.textures || []) gl.deleteTexture(t);
    this.textures = [];
    if (orig) {
      this.textures.push(texture(0, w, h, b64floats(orig)), texture(1, w, h, b64floats(dir)));
      gl.uniform1i(gl.getUniformLocation(this.prog, 'ig_test_orig'), 0);
      gl.uniform1i(gl.getUniformLocation(this.prog, 'ig_test_dir'), 1);
    }
    for (const [name, values] of Object.entries(uniforms)) {
      const loc = gl.getUniformLocation(this.prog, name);
      if (loc === null) continue;
      if (values.length === 1) gl.uniform1fv(loc, values);
      else if (name.endsWith('_params')) gl.uniform1fv(loc, values);
      else if (values.length === 2) gl.uniform2fv(loc, values);
      else if (values.length === 3) gl.uniform3fv(loc, values);
      else gl.uniform4fv(loc, values);
    }
    if (this.fbo) { gl.deleteFramebuffer(this.fbo); gl.deleteTexture(this.target); }
    this.target = texture(2, w, h, null);
    this.fbo = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.fbo);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, this.target, 0);
    gl.viewport(0, 0, w, h);
    gl.bindBuffer(gl.ARRAY_BUFFER, vbo);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
    gl.enable(gl.SCISSOR_TEST);
    return gl.checkFramebufferStatus(gl.FRAMEBUFFER) === gl.FRAMEBUFFER_COMPLETE ? '' : 'framebuffer incomplete';
  },
  band(y0, y1) {
    const t0 = performance.now();
    gl.scissor(0, y0, this.w, y1 - y0);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    const out = new Float32Array(4 * this.w * (y1 - y0));
    gl.readPixels(0, y0, this.w, y1 - y0, gl.RGBA, gl.FLOAT, out);
    const ms = performance.now() - t0;
    const err = gl.getError();
    return [floatsb64(out), ms, err];
  },
};
return '';
"""


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype=np.float32).tobytes()).decode("ascii")


class WebGL:
    """One headless Chromium with the harness page; use as a context manager (the browser is closed after)."""

    def __init__(self, timeout: float = 900.0, console_log: bool = False) -> None:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service

        opts = webdriver.ChromeOptions()
        opts.binary_location = shutil.which("chromium") or "chromium"
        for arg in FLAGS:
            opts.add_argument(arg)
        if console_log:  # the pages' console, for driver.get_log("browser")
            opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        self.driver = webdriver.Chrome(service=Service(shutil.which("chromedriver") or "chromedriver"), options=opts)
        self.driver.set_script_timeout(timeout)
        self.driver.set_page_load_timeout(timeout)
        try:
            self.harness()
        except RuntimeError:
            self.close()
            raise

    def harness(self) -> None:
        """Load the harness page (again, after the driver has visited another page, e.g. a shared page)."""
        self.driver.get("about:blank")
        err = self.driver.execute_script(surface_js().read_text(encoding="utf-8") + _HARNESS)
        if err:
            raise RuntimeError(f"headless Chromium has no usable WebGL2: {err}")

    def __enter__(self) -> WebGL:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self.driver is not None:
            self.driver.quit()
            self.driver = None

    def info(self) -> tuple[str, str]:
        """(WebGL version, renderer), e.g. ANGLE on SwiftShader."""
        version, renderer = self.driver.execute_script("return window.ig.info();")
        return version, renderer

    def compile(self, fragment: str) -> str:
        """Compile and link a fragment shader (with the harness's full-screen triangle); '' or the log."""
        return self.driver.execute_script("return window.ig.compile(arguments[0]);", fragment)

    def run(
        self,
        fragment: str,
        size: tuple[int, int],
        uniforms: dict[str, list[float]] | None = None,
        origins: np.ndarray | None = None,
        dirs: np.ndarray | None = None,
        band: int = 32,
    ) -> tuple[np.ndarray, float]:
        """Draw `fragment` over a w x h target; returns its RGBA32F pixels as (h, w, 4), row 0 at
        gl_FragCoord.y = 0.5, and the milliseconds the bands took (draw + read back). origins, dirs: (h, w, 4)."""
        log = self.compile(fragment)
        if log:
            raise RuntimeError(f"the shader did not compile:\n{log}")
        w, h = size
        err = self.driver.execute_script(
            "return window.ig.setup(arguments[0], arguments[1], arguments[2], arguments[3], arguments[4]);",
            w,
            h,
            None if origins is None else _b64(origins),
            None if dirs is None else _b64(dirs),
            {k: [float(v) for v in vals] for k, vals in (uniforms or {}).items()},
        )
        if err:
            raise RuntimeError(err)
        out = np.empty((h, w, 4), np.float32)
        total = 0.0
        for y0 in range(0, h, band):
            y1 = min(h, y0 + band)
            data, ms, glerr = self.driver.execute_script("return window.ig.band(arguments[0], arguments[1]);", y0, y1)
            if glerr:
                raise RuntimeError(f"WebGL error {glerr} drawing rows {y0}..{y1}")
            out[y0:y1] = np.frombuffer(base64.b64decode(data), np.float32).reshape(y1 - y0, w, 4)
            total += ms
        return out, total
