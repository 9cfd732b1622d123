/* The refinement of bracketed roots (runtime_c/roots_refine.c), as named cases (tests/c/ctest.h):
 * ig_refine_many against ig_refine one bracket at a time (bitwise: the batched lanes must give the very same
 * doubles, which is what makes ig_first_root equal to the first root of the full list), and both against known
 * roots, through the fast path (simple roots, from good and from useless start guesses) and through the
 * safeguarded fallback (a triple root, a root near 0 in a bracket reaching 1e27). Run under AddressSanitizer +
 * UBSan by tests/test_c_drivers_roots.py, each case reported by name. */
#include <math.h>
#include <string.h>

#include "ctest.h"
#include "poly_from_roots.h"
#include "roots_impl.h"

/* Refine k brackets of c both ways; each root must be bitwise the same and within rtol of want[i]. */
static void check(ctest *t, const char *name, const double *c, int n, int k, const double *l, const double *r,
                  const double *x0, const double *want, double rtol)
{
    double vl[IG_MAX_DEGREE + 1] = {0.0}, vr[IG_MAX_DEGREE + 1] = {0.0}, many[IG_MAX_DEGREE + 1];
    for (int i = 0; i < k; ++i) {
        vl[i] = ig_horner(c, n, l[i]);
        vr[i] = ig_horner(c, n, r[i]);
    }
    ig_refine_many(c, n, k, l, r, vl, vr, 2.0 * IG_U, x0, many);
    for (int i = 0; i < k; ++i) {
        double one = ig_refine(c, n, l[i], r[i], vl[i], vr[i], 2.0 * IG_U, x0[i]);
        int ok = memcmp(&one, &many[i], sizeof one) == 0 && one >= l[i] && one <= r[i] &&
                 fabs(one - want[i]) <= rtol * fmax(fabs(want[i]), 1e-300);
        CHECKF(t, ok, "%s, bracket %d of %d [%.17g, %.17g]: one at a time %.17g, batched %.17g, want %.17g", name, i, k,
               l[i], r[i], one, many[i], want[i]);
    }
}

/* Brackets between the midpoints of sorted simple roots; start guesses good (root + 1% of the gap), useless
 * (NaN: false position) or at a bracket end (outside the open bracket: false position too). */
static void simple_roots(ctest *t, const char *name, const double *roots, int nr, int guess)
{
    double c[IG_MAX_DEGREE + 1], l[IG_MAX_DEGREE], r[IG_MAX_DEGREE], x0[IG_MAX_DEGREE];
    int n = from_roots(roots, nr, NULL, 0, 1.0, c);
    for (int i = 0; i < nr; ++i) {
        l[i] = i == 0 ? roots[0] - 1.0 : 0.5 * (roots[i - 1] + roots[i]);
        r[i] = i == nr - 1 ? roots[nr - 1] + 1.0 : 0.5 * (roots[i] + roots[i + 1]);
        x0[i] = guess == 0 ? roots[i] + 0.01 * (r[i] - roots[i]) : guess == 1 ? NAN : l[i];
    }
    /* every batch size from 1 to nr (groups of four and the remainders) */
    for (int k = 1; k <= nr; ++k)
        check(t, name, c, n, k, l, r, x0, roots, 1e-14);
}

/* Simple roots of degree 3, 9 and 12 with the given kind of start guess. */
static void simple_roots_of_three_degrees(ctest *t, int guess)
{
    static const double r3[] = {-1.5, 0.25, 2.0};
    static const double r9[] = {-4.0, -3.0, -2.0, -1.0, 0.5, 1.0, 2.0, 3.0, 4.5};
    static const double r12[] = {-6.0, -5.0, -4.0, -3.0, -2.0, -1.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0};
    simple_roots(t, "degree 3", r3, 3, guess);
    simple_roots(t, "degree 9", r9, 9, guess);
    simple_roots(t, "degree 12", r12, 12, guess);
}

static void simple_roots_from_good_guesses(ctest *t) { simple_roots_of_three_degrees(t, 0); }

static void simple_roots_without_a_guess(ctest *t) { simple_roots_of_three_degrees(t, 1); }

static void simple_roots_guessed_at_a_bracket_end(ctest *t) { simple_roots_of_three_degrees(t, 2); }

/* a triple root: Householder converges only linearly there, the safeguarded Newton finishes; the polynomial's
 * rounding limits the accuracy to about u^(1/3) */
static void triple_root_beside_a_simple_one(ctest *t)
{
    double roots[] = {1.0, 1.0, 1.0, -2.0}, c[5];
    int n = from_roots(roots, 4, NULL, 0, 1.0, c);
    double l[] = {0.5, -3.0}, r[] = {1.7, 0.0}, x0[] = {1.6, NAN}, want[] = {1.0, -2.0};
    check(t, "triple root beside a simple one", c, n, 2, l, r, x0, want, 1e-4);
}

/* a root at 1e-13 in a bracket reaching 1e27 (|x|^n growth: bisection in the ordering of doubles) */
static void root_near_0_in_a_huge_bracket(ctest *t)
{
    double roots[] = {1e-13, -1.0, -2.0}, c[4];
    int n = from_roots(roots, 3, NULL, 0, 1.0, c);
    double l[] = {0.0, -1.5}, r[] = {1e27, -0.5}, x0[] = {NAN, NAN}, want[] = {1e-13, -1.0};
    check(t, "root near 0 in a huge bracket", c, n, 2, l, r, x0, want, 1e-14);
}

static const ctest_case CASES[] = {
    CTEST_CASE(simple_roots_from_good_guesses),        CTEST_CASE(simple_roots_without_a_guess),
    CTEST_CASE(simple_roots_guessed_at_a_bracket_end), CTEST_CASE(triple_root_beside_a_simple_one),
    CTEST_CASE(root_near_0_in_a_huge_bracket),
};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
