"""The GLSL backend: backend.py, its printer, the Chebyshev form, program assembly."""
