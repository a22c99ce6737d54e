/* Element-wise stages of spectral propagation. */
#include "holo_complex.h"

/* a *= t, element-wise. */
__kernel void multiply(__global float2 *a, __global const float2 *t)
{
    int i = get_global_id(0);
    a[i] = cmul(a[i], t[i]);
}

/* a *= w·exp(i(c - d·g)) with (w, g) packed in wg: a transfer function exp(i2πd·fz) whose
 * chirp g = 2πf²/(1/λ + fz) [rad/m] is shared by every distance d (wavefront recording planes) */
__kernel void multiply_chirp(__global float2 *a, __global const float2 *wg, float c, float d)
{
    int i = get_global_id(0);
    float2 t = wg[i];
    a[i] = t.x * cmul(a[i], cexpi(c - d * t.y));
}

#ifdef HOLO_FP64
typedef double real;
#else
typedef float real;
#endif

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

/* Spectrum rotation (Eq. 11): the target spectrum at frequency (fξ, fη) of its (ht, wt) grid
 * is the source spectrum at f = M·(fξ, fη, fζ), times the Jacobian |∂(fx,fy)/∂(fξ,fη)|;
 * waves travelling backwards in either frame are dropped. m: row-major M (target -> source
 * axes). dft, dfs: frequency steps (row, col) of target and source; c*: centre (row, col)
 * indices over the grid size, of the target (A comes centred); scale: sample areas and the
 * inverse FFT's 1/N. Global size (ht, wt). Options: -DTAPS=<n> -DES_TABLE=<entries>. */
__kernel void rotate_spectrum(__global float2 *dst, __global const float2 *A, int hs, int ws,
                              real dft_y, real dft_x, real dfs_y, real dfs_x, real inv_l2,
                              real m00, real m01, real m02, real m10, real m11, real m12,
                              real m20, real m21, real m22, real ct_y, real ct_x, float scale,
                              __global const float2 *es)
{
    int i = get_global_id(0), j = get_global_id(1), ht = get_global_size(0), wt = get_global_size(1);
    int ie = i <= (ht - 1) / 2 ? i : i - ht, jk = j <= (wt - 1) / 2 ? j : j - wt;
    real fe = ie * dft_y, fk = jk * dft_x;
    real fz2 = inv_l2 - fk * fk - fe * fe;
    float2 v = (float2)(0.0f, 0.0f);
    if (fz2 > 0) {
        real fz = sqrt(fz2);
        real fx = m00 * fk + m01 * fe + m02 * fz;
        real fy = m10 * fk + m11 * fe + m12 * fz;
        real fzs = m20 * fk + m21 * fe + m22 * fz;
        if (fzs > 0) {
            real a = m00 - m02 * fk / fz, b = m01 - m02 * fe / fz;
            real c = m10 - m12 * fk / fz, d = m11 - m12 * fe / fz;
            float jac = (float)fabs(a * d - b * c);
            float2 s = sample_spectrum_es(A, hs, ws, fx / dfs_x, fy / dfs_y, es);
            v = (scale * jac) * cmul(s, turn(-(jk * ct_x + ie * ct_y)));
        }
    }
    dst[i * wt + j] = v;
}
#endif

/* An image from its pupil's spectrum A (n, n, FFT order): pixel i reads the bin (u, v) of its
 * direction (Eq. 22); c: the pupil centre's index over n; scale: the sample area [m²]. */
__kernel void read_spectrum(__global float2 *dst, __global const float2 *A, int n,
                            __global const float *u, __global const float *v, real c,
                            float scale)
{
    int i = get_global_id(0);
    dst[i] = scale * sample_spectrum(A, n, n, u[i], v[i], c, c);
}

/* One axis of band-limited resampling: out = K · in along rows (axis 0) or columns (axis 1).
 * K is (n_out, n_in), real. Global size = out shape. */
__kernel void apply_axis0(__global float2 *out, __global const float *K,
                          __global const float2 *in, int n_in)
{
    int i = get_global_id(0), c = get_global_id(1), w = get_global_size(1);
    float2 acc = (float2)(0.0f, 0.0f);
    for (int a = 0; a < n_in; a++)
        acc += K[i * n_in + a] * in[a * w + c];
    out[i * w + c] = acc;
}

__kernel void apply_axis1(__global float2 *out, __global const float *K,
                          __global const float2 *in, int n_in)
{
    int r = get_global_id(0), j = get_global_id(1), w = get_global_size(1);
    float2 acc = (float2)(0.0f, 0.0f);
    for (int b = 0; b < n_in; b++)
        acc += K[j * n_in + b] * in[r * n_in + b];
    out[r * w + j] = acc;
}
