"""implgen: implicit surfaces f(x, y, z) = 0 turned into C and Python ray intersectors."""

__version__ = "0.1.0"
