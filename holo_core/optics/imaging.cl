/* The pupil -> image stage (imaging.py): the pupil through the iris and the lens, zero-padded,
 * and its spectrum read at the pixels. Arrays are in FFT order: sample (row r, col c) of an
 * (h, w) grid lies at signed index (r or r - h, c or c - w). */
#include "spectrum_read.h"
#include "fft_order.h"

/* Q (2h, 2w) at the pupil's samples: P·w(ρ)·exp(−ik(√(ρ² + f²) − f))·d(x)·d(y), the iris w
 * (1 inside (1 − taper)·radius, a raised cosine to 0 at the radius [m]), the thin lens of
 * Eq. 24 focused at f [m] (f = 0: none), and the deapodization d of the ES read that follows;
 * the rest of Q is left as it is (the FFT takes it as zero). Global size: by_rows of P. */
__kernel void pupil_window(__global float2 *Q, __global const float2 *P, int h, int w,
                           float dy, float dx, float radius, float taper, float k, float f,
                           __global const float *dy_apod, __global const float *dx_apod)
{
    int c = get_global_id(0), r = get_global_id(1);
    if (c >= w)
        return;
    int sr = signed_index(r, h), sc = signed_index(c, w);
    float y = sr * dy, x = sc * dx, rho = sqrt(x * x + y * y);
    float inner = (1.0f - taper) * radius, win = 1.0f;
    if (rho >= radius)
        win = 0.0f;
    else if (rho > inner)
        win = 0.5f * (1.0f + cos(M_PI_F * (rho - inner) / (radius - inner)));
    float2 v = (win * dy_apod[r] * dx_apod[c]) * P[r * w + c];
    if (f > 0)
        v = cmul(v, cexpi(-k * rho * rho / (sqrt(rho * rho + f * f) + f)));
    int H = 2 * h, W = 2 * w;
    Q[(sr < 0 ? sr + H : sr) * W + (sc < 0 ? sc + W : sc)] = v;
}

/* out[i] = scale·Â(u[i], v[i]): the pupil's spectrum at each pixel's direction cosines
 * (Eq. 22), in bins of the padded (h, w) grid, read with the ES kernel (-DTAPS, -DES_TABLE). */
__kernel void read_pixels(__global float2 *out, __global const float2 *A, int h, int w,
                          __global const float *u, __global const float *v, float scale,
                          __global const float2 *es)
{
    int i = get_global_id(0);
    out[i] = scale * sample_spectrum_es(A, h, w, u[i], v[i], es);
}

/* The speckle's box low-pass and sampling (Sect. VII-E), before the images leave the device:
 * camera pixel (row y, col x) of a W-pixel row from its s×s fine pixels of A (W·s wide), the
 * mean of |A|² (block_power), and the mean of A·conj(B) added to out where add != 0
 * (block_cross: the depth pair's cross image, summed over the colours at its wavelength).
 * Global size (W, H). */
__kernel void block_power(__global float *out, __global const float2 *A, int s, int W)
{
    int x = get_global_id(0), y = get_global_id(1);
    float sum = 0.0f;
    for (int i = 0; i < s; i++) {
        __global const float2 *row = A + (size_t)(y * s + i) * W * s + x * s;
        for (int j = 0; j < s; j++)
            sum += dot(row[j], row[j]);
    }
    out[y * W + x] = sum / (s * s);
}

__kernel void block_cross(__global float2 *out, __global const float2 *A,
                          __global const float2 *B, int s, int W, int add)
{
    int x = get_global_id(0), y = get_global_id(1);
    float2 sum = (float2)(0.0f, 0.0f);
    for (int i = 0; i < s; i++) {
        size_t at = (size_t)(y * s + i) * W * s + x * s;
        for (int j = 0; j < s; j++)
            sum += cmul(A[at + j], cconj(B[at + j]));
    }
    sum /= (float)(s * s);
    out[y * W + x] = add ? out[y * W + x] + sum : sum;
}
