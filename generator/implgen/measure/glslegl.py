"""GLSL on desktop OpenGL through EGL without a window (moderngl, backend 'egl'): Mesa's llvmpipe on a machine
without a GPU, the GPU's driver on one with. The same `run` as `implgen.measure.webgl.WebGL`, so
`implgen.measure.glslcheck` and bench/glsl_compare.py take either.

llvmpipe compiles the shader to the CPU's vector instructions: its pixels are a float32 GPU's, its frame times
are a CPU's (indicative only). Programs are desktop GLSL 4.50 (`dialect`), the same runtime and shapes as the
browser's GLSL ES 3.00.

moderngl is imported only when an `Egl` is made; without it, or without an EGL driver, `Egl()` raises
RuntimeError saying why (tests skip on it).
"""

from __future__ import annotations

import time

import numpy as np

_INT_TYPES = (0x1404, 0x8B53, 0x8B54, 0x8B55, 0x8B56)  # GL_INT, its vectors, GL_BOOL
VERTEX = "#version 450\nin vec2 p;\nvoid main() { gl_Position = vec4(p, 0.0, 1.0); }\n"


class Egl:
    """One headless OpenGL 4.5 context; use as a context manager (released after)."""

    dialect = "450"  # the header implgen.codegen.backends.glsl.program gives its programs

    def __init__(self) -> None:
        try:
            import moderngl
        except ImportError as exc:
            raise RuntimeError("moderngl is not installed (pip install moderngl)") from exc
        try:
            self.ctx = moderngl.create_standalone_context(backend="egl", require=450)
        except Exception as exc:  # moderngl raises plain Exception when EGL or GL 4.5 is missing
            raise RuntimeError(f"no OpenGL 4.5 context through EGL: {exc}") from exc
        tri = np.array([-1.0, -1.0, 3.0, -1.0, -1.0, 3.0], np.float32)
        self.vbo = self.ctx.buffer(tri.tobytes())
        self.programs: dict[str, object] = {}  # the last few programs by their text: a second run draws warm

    def __enter__(self) -> Egl:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self.ctx is not None:
            for prog in self.programs.values():
                prog.release()
            self.programs.clear()
            self.ctx.release()
            self.ctx = None

    def info(self) -> tuple[str, str]:
        """(GL version, renderer), e.g. llvmpipe."""
        return self.ctx.info["GL_VERSION"], self.ctx.info["GL_RENDERER"]

    def compile(self, fragment: str):
        """The linked program (VERTEX and `fragment`), kept for the next run of the same text (a driver compiles
        on the first draw: that draw's time holds the compile); raises RuntimeError with the compiler's log."""
        if fragment in self.programs:
            return self.programs[fragment]
        try:
            prog = self.ctx.program(vertex_shader=VERTEX, fragment_shader=fragment)
        except Exception as exc:  # moderngl.Error
            raise RuntimeError(f"the shader did not compile:\n{exc}") from exc
        if len(self.programs) >= 4:
            self.programs.pop(next(iter(self.programs))).release()
        self.programs[fragment] = prog
        return prog

    def _texture(self, data: np.ndarray, unit: int):
        h, w = data.shape[:2]
        tex = self.ctx.texture((w, h), 4, np.ascontiguousarray(data, np.float32).tobytes(), dtype="f4")
        tex.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        tex.use(unit)
        return tex

    @staticmethod
    def _set_uniforms(prog, uniforms: dict[str, list[float]]) -> None:
        """Each named uniform the program uses, from its values in order (a whole array at once); ints for int
        uniforms."""
        for name, values in uniforms.items():
            if name not in prog:
                continue
            u = prog[name]
            dtype = "i4" if u.gl_type in _INT_TYPES else "f4"
            u.write(np.asarray(values, dtype=dtype).tobytes())

    def run(
        self,
        fragment: str,
        size: tuple[int, int],
        uniforms: dict[str, list[float]] | None = None,
        origins: np.ndarray | None = None,
        dirs: np.ndarray | None = None,
        band: int = 32,
    ) -> tuple[np.ndarray, float]:
        """Draw `fragment` over a w x h RGBA32F target, in bands of rows (each finished before the next);
        returns the pixels as (h, w, 4), row 0 at gl_FragCoord.y = 0.5, and the bands' milliseconds (draw and
        read back). origins, dirs: (h, w, 4), bound as ig_test_orig and ig_test_dir."""
        prog = self.compile(fragment)
        w, h = size
        held = []
        try:
            if origins is not None:
                held += [self._texture(origins, 0), self._texture(dirs, 1)]
                for name, unit in (("ig_test_orig", 0), ("ig_test_dir", 1)):
                    if name in prog:
                        prog[name].value = unit
            self._set_uniforms(prog, uniforms or {})
            target = self.ctx.texture((w, h), 4, dtype="f4")
            fbo = self.ctx.framebuffer(color_attachments=[target])
            vao = self.ctx.vertex_array(prog, [(self.vbo, "2f", "p")])
            held += [target, fbo, vao]
            return self._bands(fbo, vao, size, band)
        finally:
            for obj in reversed(held):
                obj.release()

    def _bands(self, fbo, vao, size, band: int) -> tuple[np.ndarray, float]:
        w, h = size
        fbo.use()
        out = np.empty((h, w, 4), np.float32)
        total = 0.0
        for y0 in range(0, h, band):
            y1 = min(h, y0 + band)
            t0 = time.perf_counter()
            fbo.scissor = (0, y0, w, y1 - y0)
            vao.render(self.ctx.TRIANGLES, vertices=3)
            data = fbo.read(viewport=(0, y0, w, y1 - y0), components=4, dtype="f4")
            total += 1000.0 * (time.perf_counter() - t0)
            out[y0:y1] = np.frombuffer(data, np.float32).reshape(y1 - y0, w, 4)
        return out, total
