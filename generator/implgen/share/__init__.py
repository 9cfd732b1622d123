"""`implgen share`: one self-contained HTML page that draws a shape with its GLSL in any WebGL2 browser."""
