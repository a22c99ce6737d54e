/* Element-wise stages of spectral propagation. */
#include "spectrum_read.h"

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

#ifdef TAPS
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
