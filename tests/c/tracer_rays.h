/* What the two files of the tracer's ray-level test share (tracer_rays.c: spheres, CSG, transforms, and main;
 * tracer_rays_optics.c: optics, shading, glass, the tracer's shortcuts): the failure count, CHECK, and small
 * scene helpers. */
#ifndef IMPLGEN_TEST_TRACER_RAYS_H
#define IMPLGEN_TEST_TRACER_RAYS_H

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

/* failed checks so far (defined in tracer_rays.c) */
extern int failures;

#define CHECK(cond, ...)                                                                                               \
    do {                                                                                                               \
        if (!(cond)) {                                                                                                 \
            ++failures;                                                                                                \
            printf("FAIL %s:%d: ", __FILE__, __LINE__);                                                                \
            printf(__VA_ARGS__);                                                                                       \
            printf("\n");                                                                                              \
        }                                                                                                              \
    } while (0)

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

/* tracer_rays_optics.c */
void test_optics(void);
void test_unbounded_and_shading(void);
void test_glass(void);
void test_shortcuts(void);
void test_plane_path(void);

#endif
