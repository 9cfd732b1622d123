"""Case sets and reference answers that only the benchmarks and the tests use: polynomials with known roots and
ray polynomials of the example shapes (polys.py), degree 12-24 ray sets (rays_high.py), roots over 150 decades
and far-origin rays (extreme.py), and exact root isolation and scoring (reference.py). Nothing of the pipeline
imports them."""
