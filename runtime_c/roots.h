/* Real roots of a polynomial c[0] + c[1] t + ... + c[n] t^n on a closed interval.
 *
 * Contract (relied on by the generated intersectors, the tracer and the Python binding):
 *  - coefficients lowest power first; double precision;
 *  - all DISTINCT real roots in [lo, hi] (inclusive), ascending; a root of even multiplicity
 *    (a grazing ray: p touches zero without changing sign) is reported once;
 *  - vanishing leading coefficients lower the degree (never a division by zero);
 *  - NaN or Inf among the coefficients, or lo > hi, or NaN bounds: no roots;
 *  - never returns NaN, never loops without bound, no global mutable state.
 */
#ifndef IMPLGEN_ROOTS_H
#define IMPLGEN_ROOTS_H

/* Highest polynomial degree the solvers accept (the generator refuses anything above). */
#define IG_MAX_DEGREE 24

typedef enum {
    IG_ROOTS_AUTO = 0,     /* the best method for the degree, as the solver report shows */
    IG_ROOTS_CLOSED = 1,   /* closed forms up to degree 4 (falls back to IG_ROOTS_BRACKET above) */
    IG_ROOTS_STURM = 2,    /* Sturm sequence isolation + safeguarded refinement */
    IG_ROOTS_BRACKET = 3,  /* derivative bracketing (recursive roots of p') + safeguarded refinement */
    IG_ROOTS_BERNSTEIN = 4 /* isolation by Bernstein subdivision + the same refinement; bracketing where unsure */
} ig_root_method;

/* Writes at most n roots to roots[] (caller provides room for IG_MAX_DEGREE) and returns their count.
 * n is the nominal degree (c has n + 1 entries), 0 <= n <= IG_MAX_DEGREE; n out of range gives 0. */
int ig_real_roots(const double *c, int n, double lo, double hi, ig_root_method method, double *roots);

/* The smallest root in [lo, hi] -- the same value ig_real_roots would list first -- into *root; returns 1, or 0
 * when there is none. What a ray needs for its nearest hit: AUTO and BERNSTEIN stop at the leftmost piece
 * of the subdivision that holds a root instead of isolating every root. */
int ig_first_root(const double *c, int n, double lo, double hi, ig_root_method method, double *root);

#endif
