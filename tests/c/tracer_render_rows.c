/* Bands of rows (rt_render_set_rows): every band, rendered on any number of threads, is bit for bit those rows
 * of the whole image, and bad ranges are refused. Named cases (tests/c/ctest.h), built by tests/test_tracer_c.py
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

static const ctest_case CASES[] = {
    CTEST_CASE(each_band_is_those_rows_of_the_whole_image),
    CTEST_CASE(empty_negative_and_outside_row_ranges_are_refused),
};

int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }
