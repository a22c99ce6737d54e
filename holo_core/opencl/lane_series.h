/* What the per-segment recurrence kernels share (plate/point_sum.cl, plate/zone_sum.cl): a
 * work item's VEC rows as the lanes of a float vector (floatv; VEC must be defined), REAL
 * (double where the device has it) for the exact phases, and the short series that stand in
 * for exp and sincos, whose arguments there are small. */
#ifndef HOLO_LANE_SERIES_H
#define HOLO_LANE_SERIES_H
#include "holo_complex.h"

#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
#include "real.h"

#if VEC == 1
typedef float floatv;
#define LANE_ID(c) 0.0f
#define UNLANE(v, lanes) ((lanes)[0] = (v))      /* the lanes of v into the floats lanes[] */
#else
typedef CAT(float, VEC) floatv;
#define LANE_ID(c) CAT(vload, VEC)(0, c)
#define UNLANE(v, lanes) CAT(vstore, VEC)(v, 0, lanes)
#endif

__constant float LANES[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};

/* Builtin exp and sincos are library calls on PoCL, slower than the whole recurrence: the
 * arguments here are small, so short series do (errors below 1e-8). */
static floatv wrap(floatv x)            /* x reduced to [-pi, pi] */
{
    return x - 6.28318531f * rint(x * 0.159154943f);
}

static floatv exp_small(floatv x)       /* exp(x), |x| << 1 (a relative amplitude change) */
{
    return 1 + x * (1 + x * (0.5f + x * (1 / 6.0f + x * (1 / 24.0f + x * (1 / 120.0f
           + x * (1 / 720.0f))))));
}

/* (re, im) = m * exp(i x) for x in [-pi, pi] */
#define CIS(x, m, re, im)                  \
    do {                                   \
        floatv cos_, sin_;                 \
        HOLO_CIS(floatv, x, cos_, sin_);   \
        re = (m) * cos_;                   \
        im = (m) * sin_;                   \
    } while (0)

#endif
