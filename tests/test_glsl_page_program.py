"""The shared page's fragment shader against the GLSL test harness's ray program, by structure: how many times
each holds the shape's tree once every call is inlined (implgen.measure.glslcalls), as a GPU compiler inlines them.

The page's program is put together by the page's own surface.js (IgSurface.fragmentSource) in a plain headless
Chromium; the harness's by implgen.measure.glslcheck. On a GPU a page that held the tree eight times (a call of
the shape's hit for the camera and one for the shadows, f at points in three more places) drew a degree 16-24
Chebyshev form 9-13 times slower than the harness on the same pixels; the page now asks every question of the
shape through one loop and holds the tree once, like the harness.
"""

from __future__ import annotations

import pytest

import page_shader
from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import HEADERS, program, runtime_text, shape_defines
from implgen.measure import glslcases, glslcheck
from implgen.measure.glslcalls import inlined_copies
from implgen.resources import surface_js

pytestmark = pytest.mark.needs_program("chromium", "chromedriver")


@pytest.fixture(scope="module")
def driver():
    d = page_shader.plain_chromium()
    yield d
    d.quit()


def _page_fragment(driver, spec) -> str:
    data = {"glsl_name": glsl_name(spec.name), "shape": glslcheck.glsl_text(spec), "runtime": runtime_text()}
    data["header"] = HEADERS["es"]
    return driver.execute_script(surface_js().read_text(encoding="utf-8") + page_shader.ASSEMBLE, data)


def _ray_program(spec) -> str:
    prefix = glsl_name(spec.name)
    return program([glslcheck.glsl_text(spec)], glslcheck.RAY_MAIN, "es", shape_defines(prefix))


def test_the_copy_counter_counts_inlined_calls():
    text = """
#define CALL_B b
float c(float x) { return x; }
float b(float x)
{
    return c(x) + c(2.0 * x);
}
float a(float x) { return CALL_B(x) * b(x); }
void main() { float y = a(1.0) + c(a(2.0)); }
"""
    assert inlined_copies(text, "a") == 2
    assert inlined_copies(text, "b") == 4
    assert inlined_copies(text, "c") == 9  # 2 a x 2 b x 2 c, and one in main


@pytest.mark.parametrize("n", [16, 24])
def test_the_page_holds_the_tree_as_often_as_the_ray_program(driver, n):
    """The Chebyshev form of an expanded Chmutov surface (the largest trees the GLSL evaluates): its affine
    form and its normal once each in the page, as in the harness's program."""
    spec = glslcases.chmutov(n, nested=False)
    prefix = glsl_name(spec.name)
    page, ray = _page_fragment(driver, spec), _ray_program(spec)
    for function in ("raa", "normal"):
        assert inlined_copies(ray, f"{prefix}_{function}") == 1
        assert inlined_copies(page, f"{prefix}_{function}") == 1, function
    assert inlined_copies(page, f"{prefix}_hit") <= 1
