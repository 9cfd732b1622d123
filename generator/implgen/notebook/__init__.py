"""`implgen.show`: a surface or a scene in a Jupyter notebook, as an anywidget (docs/notebook.md).

`source.py` reads what show() is given (a spec file, a scene file, or an equation and its params), `picture.py`
renders the kernel's pictures in double with the C tracer (the fallback without WebGL2, a scene's frames, and
`_repr_png_`), `widget.py` holds the widgets and show(); `static/widget.js` is the widget's view, drawing with
share/static/'s renderer (surface.js, orbit.js), the same code as the shared page.
"""
