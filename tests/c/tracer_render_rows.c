/* Bands of rows (rt_render_set_rows): every band, rendered on any number of threads, is bit for bit those rows
 * of the whole image, and bad ranges are refused. Passes (rt_render_set_pass): samples added in passes, the
 * pixels with even x and y first, make the whole image bit for bit, and bad passes are refused. Named cases (tests/c/ctest.h), built by tests/test_tracer_c.py
 * with the sanitizers and linked with the runtime and the generated sphere and torus_z; each case reported by
 * name. */
#include "tracer_rays.h"

enum { W = 40, H = 29, SPP = 3 };

static rt_scene *two_shapes(ctest *t)
{
    rt_scene *s = rt_scene_new();
    double m[12], r = 1.0, torus[2] = {1.0, 0.3}, eye[3] = {0, 1.5, 6}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    double light[3] = {3, 8, 4}, white[3] = {1, 1, 1};
    int mat = add_matte(s);
    translate_scale(m, -1.2, 0, 0, 1.0);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &sphere_shape, &r, 1, m, mat));
    translate_scale(m, 1.2, 0, 0, 1.0);
    rt_scene_add_object(s, rt_scene_add_leaf(s, &torus_z_shape, torus, 2, m, mat));
    rt_scene_add_light(s, light, white);
    rt_scene_set_camera(s, eye, at, up, 40.0);
    CHECKF(t, rt_scene_commit(s) == 0, "commit: %s", rt_scene_error(s));
    return s;
}

static void render_band(ctest *t, const rt_scene *s, int y0, int y1, int threads, float *out)
{
    rt_render *r = rt_render_new(s, W, H, SPP, 4, threads, 7);
    CHECKF(t, r != NULL, "rt_render_new");
    if (!r)
        return;
    CHECKF(t, rt_render_set_rows(r, y0, y1) == 0, "rows [%d, %d)", y0, y1);
    CHECKF(t, rt_render_run(r, out) == 0, "run [%d, %d)", y0, y1);
    CHECKF(t, rt_render_progress(r) == y1 - y0, "progress %d, want %d", rt_render_progress(r), y1 - y0);
    rt_render_free(r);
}

/* a band's rows as the whole image has them, bands of 1 to 11 rows on 1, 2 and 3 threads */
static void each_band_is_those_rows_of_the_whole_image(ctest *t)
{
    float whole[W * H * 3], band[W * H * 3];
    const int edges[] = {0, 1, 5, 6, 17, 28, H};
    rt_scene *s = two_shapes(t);
    rt_render *r = rt_render_new(s, W, H, SPP, 4, 3, 7);
    size_t row = (size_t)W * 3;
    int i, covered = 0, bands = (int)(sizeof edges / sizeof edges[0]) - 1;
    CHECKF(t, rt_render_run(r, whole) == 0, "whole image");
    rt_render_free(r);
    for (i = 0; i < bands; ++i) {
        int y0 = edges[i], y1 = edges[i + 1];
        render_band(t, s, y0, y1, 1 + i % 3, band);
        CHECKF(t, memcmp(band, whole + (size_t)y0 * row, (size_t)(y1 - y0) * row * sizeof(float)) == 0,
               "band [%d, %d) differs from the whole image", y0, y1);
        covered += y1 - y0;
    }
    CHECKF(t, covered == H, "bands cover %d rows", covered);
    rt_scene_free(s);
    printf("render rows: %d bands\n", bands);
}

/* after the whole image was rendered, as a band's caller would */
static void empty_negative_and_outside_row_ranges_are_refused(ctest *t)
{
    float whole[W * H * 3];
    rt_scene *s = two_shapes(t);
    rt_render *r = rt_render_new(s, W, H, SPP, 4, 3, 7);
    CHECKF(t, rt_render_run(r, whole) == 0, "whole image");
    CHECKF(t, rt_render_set_rows(r, -1, 3) == -1 && rt_render_set_rows(r, 3, 3) == -1, "empty or negative range");
    CHECKF(t, rt_render_set_rows(r, 0, H + 1) == -1 && rt_render_set_rows(NULL, 0, 1) == -1, "past the image");
    rt_render_free(r);
    rt_scene_free(s);
}

/* the viewer's ladder: sample 0 of the even pixels, then of the others, then samples 1 .. SPP-1 one by one, on a
 * band of rows and on 1 to 3 threads: the band of the whole image, bit for bit; between passes, the mean so far */
static void passes_add_up_to_the_whole_image(ctest *t)
{
    static float whole[W * H * 3], out[W * H * 3];
    static double sums[W * H * 3];
    const int y0 = 3, y1 = 26;
    const size_t row = (size_t)W * 3;
    rt_scene *s = two_shapes(t);
    rt_render *r = rt_render_new(s, W, H, SPP, 4, 2, 7);
    int k, x, same_even = 1, odd_untouched = 1;
    CHECKF(t, rt_render_run(r, whole) == 0, "whole image");
    rt_render_free(r);
    r = rt_render_new(s, W, H, SPP, 4, 3, 7);
    memset(out, 0xff, sizeof out); /* NaN: a pixel a pass should not touch stays NaN */
    CHECKF(t, rt_render_set_rows(r, y0, y1) == 0, "rows");
    CHECKF(t, rt_render_set_pass(r, 0, 1, RT_PIXELS_EVEN, sums) == 0 && rt_render_run(r, out) == 0, "even pass");
    for (x = 0; x < W; ++x) {
        size_t at = (size_t)(4 - y0) * row + (size_t)x * 3; /* row 4: even */
        odd_untouched &= (x % 2 == 1) == isnan(out[at]);
        same_even &= x % 2 == 1 || (float)sums[at] == out[at];
    }
    CHECKF(t, odd_untouched && same_even, "the even pass wrote the even pixels only, their first sample");
    CHECKF(t, rt_render_set_pass(r, 0, 1, RT_PIXELS_ODD, sums) == 0 && rt_render_run(r, out) == 0, "odd pass");
    for (k = 1; k < SPP; ++k) {
        rt_render_free(r); /* a pass needs only the sums: a fresh context on another thread count goes on */
        r = rt_render_new(s, W, H, SPP, 4, 1 + k % 3, 7);
        CHECKF(t, rt_render_set_rows(r, y0, y1) == 0, "rows");
        CHECKF(t, rt_render_set_pass(r, k, k + 1, RT_PIXELS_ALL, sums) == 0 && rt_render_run(r, out) == 0, "pass %d",
               k);
    }
    CHECKF(t, memcmp(out, whole + (size_t)y0 * row, (size_t)(y1 - y0) * row * sizeof(float)) == 0,
           "the passes differ from the whole image");
    rt_render_free(r);
    rt_scene_free(s);
}

static void bad_passes_are_refused(ctest *t)
{
    static double sums[W * H * 3];
    rt_scene *s = two_shapes(t);
    rt_render *r = rt_render_new(s, W, H, SPP, 4, 1, 7);
    CHECKF(t, rt_render_set_pass(r, -1, 1, RT_PIXELS_ALL, sums) == -1, "negative first sample");
    CHECKF(t, rt_render_set_pass(r, 1, 1, RT_PIXELS_ALL, sums) == -1, "no samples");
    CHECKF(t, rt_render_set_pass(r, 0, SPP + 1, RT_PIXELS_ALL, sums) == -1, "past spp");
    CHECKF(t, rt_render_set_pass(r, 0, 1, 3, sums) == -1 && rt_render_set_pass(r, 0, 1, -1, sums) == -1, "pixels");
    CHECKF(t, rt_render_set_pass(r, 0, 1, RT_PIXELS_ALL, NULL) == -1, "no sums");
    CHECKF(t, rt_render_set_pass(NULL, 0, 1, RT_PIXELS_ALL, sums) == -1, "no context");
    rt_render_free(r);
    rt_scene_free(s);
}

static const ctest_case CASES[] = {
    CTEST_CASE(each_band_is_those_rows_of_the_whole_image),
    CTEST_CASE(empty_negative_and_outside_row_ranges_are_refused),
    CTEST_CASE(passes_add_up_to_the_whole_image),
    CTEST_CASE(bad_passes_are_refused),
};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
