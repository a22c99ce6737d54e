/* Complex helpers shared by every kernel: a complex number is a float2 (re, im). */
#ifndef HOLO_COMPLEX_H
#define HOLO_COMPLEX_H

inline float2 cmul(float2 a, float2 b)
{
    return (float2)(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}

inline float2 cconj(float2 a) { return (float2)(a.x, -a.y); }

/* exp(i*phase) */
inline float2 cexpi(float phase)
{
    float c, s = sincos(phase, &c);
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
