/* Complex helpers shared by every kernel: a complex number is a float2 (re, im). */
#ifndef HOLO_COMPLEX_H
#define HOLO_COMPLEX_H

inline float2 cmul(float2 a, float2 b)
{
    return (float2)(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}

inline float2 cconj(float2 a) { return (float2)(a.x, -a.y); }

/* (c, s) = (cos x, sin x) for |x| <= π, x of any float vector type T: Taylor series at x/2,
 * then the double angle (error < 1e-7). Pure arithmetic: PoCL's sincos is a library call,
 * slower than this and a barrier to its vectoriser. */
#define HOLO_CIS(T, x, c, s)                                                                 \
    do {                                                                                     \
        T h_ = 0.5f * (x), q_ = h_ * h_;                                                     \
        T s_ = h_ * (1 + q_ * (-1 / 6.0f + q_ * (1 / 120.0f + q_ * (-1 / 5040.0f             \
               + q_ * (1 / 362880.0f + q_ * (-1 / 39916800.0f + q_ * (1 / 6227020800.0f)))))));\
        T c_ = 1 + q_ * (-0.5f + q_ * (1 / 24.0f + q_ * (-1 / 720.0f + q_ * (1 / 40320.0f    \
               + q_ * (-1 / 3628800.0f + q_ * (1 / 479001600.0f))))));                      \
        c = c_ * c_ - s_ * s_;                                                               \
        s = 2 * s_ * c_;                                                                     \
    } while (0)

/* exp(i*phase), any float phase: reduced to [-π, π] first */
inline float2 cexpi(float phase)
{
    float x = phase - 6.28318531f * rint(phase * 0.159154943f), c, s;
    HOLO_CIS(float, x, c, s);
    return (float2)(c, s);
}

#ifdef HOLO_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
inline double2 zmul(double2 a, double2 b)
{
    return (double2)(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}
#endif

#endif
