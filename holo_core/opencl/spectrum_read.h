/* Reading a spectrum between its bins: the kernels' `real`, turn(), a bilinear read and the
 * ES-kernel read of a non-uniform FFT. Shared by propagation/tilt.cl and optics/imaging.cl. */
#ifndef HOLO_SPECTRUM_READ_H
#define HOLO_SPECTRUM_READ_H
#include "holo_complex.h"

#include "real.h"

/* exp(i2π·t), with t reduced to [-0.5, 0.5] in REAL precision first. */
inline float2 turn(real t)
{
    return cexpi((float)(2 * M_PI * (t - rint(t))));
}

/* Bilinear sample of spectrum A (h, w, FFT order) at continuous bin (u, v) = (col, row) in
 * signed frequency units; zero beyond the bins the grid holds. The FFT puts the origin at index
 * 0; (cu, cv) = (centre column / w, centre row / h) move it to the field's centre, so that the
 * spectrum interpolated is the smooth one of the centred field. */
inline float2 sample_spectrum(__global const float2 *A, int h, int w, real u, real v,
                              real cu, real cv)
{
    int u0 = (int)floor(u), v0 = (int)floor(v);
    float fu = (float)(u - u0), fv = (float)(v - v0);
    /* the centring phase at (u0, v0), and its steps to the next column and row */
    float2 at = turn(u0 * cu + v0 * cv), step_u = turn(cu), step_v = turn(cv);
    float2 acc = (float2)(0.0f, 0.0f);
    for (int dv = 0; dv < 2; dv++, at = cmul(at, step_v)) {
        int m = v0 + dv;
        float2 ph = at;
        float wv = dv ? fv : 1.0f - fv;
        for (int du = 0; du < 2; du++, ph = cmul(ph, step_u)) {
            int n = u0 + du;
            if (m < -(h / 2) || m > (h - 1) / 2 || n < -(w / 2) || n > (w - 1) / 2)
                continue;
            float wgt = wv * (du ? fu : 1.0f - fu);
            acc += wgt * cmul(A[(m < 0 ? m + h : m) * w + (n < 0 ? n + w : n)], ph);
        }
    }
    return acc;
}

/* Centred spectrum A (h, w, FFT order) at continuous bin (u, v), interpolated with TAPS × TAPS
 * weights of the "exponential of semicircle" kernel exp(β(√(1 - (2t/TAPS)²) - 1)) (Barnett et
 * al., FINUFFT), read from `es` (ES_TABLE (value, slope) pairs over t in [-TAPS/2, TAPS/2]):
 * PoCL's exp and sqrt are library calls. Interpolating multiplies the field by the kernel's
 * Fourier transform, which the caller divides out of the source beforehand (tilt.py); the
 * source's copies at whole padded periods that it also makes are ~10^-(TAPS-1) weak. */
#ifdef TAPS
inline float es_weight(__global const float2 *es, float t)
{
    float x = (t + 0.5f * TAPS) * ((float)ES_TABLE / TAPS);
    int i = (int)floor(x);
    if (i < 0 || i >= ES_TABLE)
        return 0.0f;
    float2 e = es[i];
    return e.x + (x - i) * e.y;
}

inline float2 sample_spectrum_es(__global const float2 *A, int h, int w, real u, real v,
                                 __global const float2 *es)
{
    int u0 = (int)floor(u) - TAPS / 2 + 1, v0 = (int)floor(v) - TAPS / 2 + 1;
    float fu = (float)(u - u0), fv = (float)(v - v0);
    float wu[TAPS];
    for (int du = 0; du < TAPS; du++)
        wu[du] = es_weight(es, fu - du);
    float2 acc = (float2)(0.0f, 0.0f);
    for (int dv = 0; dv < TAPS; dv++) {
        int m = v0 + dv;
        if (m < -(h / 2) || m > (h - 1) / 2)
            continue;
        __global const float2 *row = A + (m < 0 ? m + h : m) * w;
        float2 sum = (float2)(0.0f, 0.0f);
        for (int du = 0; du < TAPS; du++) {
            int n = u0 + du;
            if (n >= -(w / 2) && n <= (w - 1) / 2)
                sum += wu[du] * row[n < 0 ? n + w : n];
        }
        acc += es_weight(es, fv - dv) * sum;
    }
    return acc;
}

#endif
#endif
