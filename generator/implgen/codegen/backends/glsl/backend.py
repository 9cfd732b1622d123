"""The GLSL backend: one shader file (templates/glsl/) for WebGL2 and GLSL 4.50, in float with every rounding
counted (printer.py); f's Chebyshev form in its box where that is tighter (chebform.py); whole programs from the
runtime_glsl/ sources (program.py)."""

from __future__ import annotations

from implgen.codegen.backends.contract import Backend
from implgen.codegen.backends.glsl.printer import GLSLPrinter, glsl_extra

BACKEND = Backend("glsl", (("shape.glsl.j2", "{name}.glsl"),), GLSLPrinter, glsl_extra)
