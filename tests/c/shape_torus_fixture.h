#ifndef SHAPE_TORUS_FIXTURE_H
#define SHAPE_TORUS_FIXTURE_H
#include "shape.h"
extern const ig_shape shape_torus_fixture;
#endif
