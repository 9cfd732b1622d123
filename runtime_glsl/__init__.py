"""Package marker: lets setuptools ship the GLSL runtime sources as package data."""
