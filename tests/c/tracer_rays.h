/* What the two files of the tracer's ray-level test share (tracer_rays.c: spheres, CSG, transforms, and main with
 * the table of cases; tracer_rays_optics.c: optics, shading, glass, the tracer's shortcuts): the named-case
 * harness (tests/c/ctest.h), small scene helpers, and the cases of tracer_rays_optics.c. tracer_render_rows.c
 * uses the helpers too. */
#ifndef IMPLGEN_TEST_TRACER_RAYS_H
#define IMPLGEN_TEST_TRACER_RAYS_H

#include "ctest.h"
#include "tracer_internal.h"
#include "sphere.h"
#include "torus_z.h"
#include "piriform.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#ifndef M_SQRT1_2
#define M_SQRT1_2 0.70710678118654752440
#endif

static const double IDENTITY[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

static inline double urand(unsigned long long *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

static inline int add_matte(rt_scene *s)
{
    double m[RT_MATERIAL_DOUBLES] = {0.8, 0.8, 0.8, 0, 0, 0, 0, 0.1, 0.9, 0, 10, 0, 0, 1.5, 0, 0, 0, 0, 0};
    return rt_scene_add_material(s, m);
}

static inline void translate_scale(double m[12], double tx, double ty, double tz, double k)
{
    memset(m, 0, 12 * sizeof(double));
    m[0] = m[5] = m[10] = k;
    m[3] = tx;
    m[7] = ty;
    m[11] = tz;
}

/* R (row-major 3x3): the rotation by ang radians about axis (Rodrigues). */
static inline void rot_axis(const double axis[3], double ang, double R[9])
{
    double c = cos(ang), sn = sin(ang), l = sqrt(rt_dot(axis, axis)), x = axis[0] / l, y = axis[1] / l, z = axis[2] / l;
    R[0] = c + x * x * (1 - c);
    R[1] = x * y * (1 - c) - z * sn;
    R[2] = x * z * (1 - c) + y * sn;
    R[3] = y * x * (1 - c) + z * sn;
    R[4] = c + y * y * (1 - c);
    R[5] = y * z * (1 - c) - x * sn;
    R[6] = z * x * (1 - c) - y * sn;
    R[7] = z * y * (1 - c) + x * sn;
    R[8] = c + z * z * (1 - c);
}

/* the cases of tracer_rays_optics.c */
void snell_on_random_rays(ctest *t);
void total_internal_reflection_beyond_the_critical_angle(ctest *t);
void fresnel_at_normal_incidence_brewster_and_grazing(ctest *t);
void mirror_reflection(ctest *t);
void point_light_shading_and_shadow(ctest *t);
void glass_ball_beer_lambert(ctest *t);
void total_internal_reflection_traps_a_ray_in_a_ball(ctest *t);
void index_matched_absorbing_csg_shell(ctest *t);
void shadow_through_glass(ctest *t);
void shortcuts_on_20000_random_rays(ctest *t);
void checker_colour_beyond_2_53(ctest *t);
void plane_path_against_long_double_and_the_general_solve(ctest *t);
void plane_path_parallel_inside_and_beyond_far(ctest *t);

#endif
