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
                           __global const float *dy_apod, __global const float *dx_apod,
                           int plane)
{
    Q += (size_t)plane * 4 * h * w;   /* plane `plane` of stacks of P and Q */
    P += (size_t)plane * h * w;
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

/* Every look's images read at the fine pixels and folded to the camera's pixels at once (the
 * speckle's box low-pass and sampling, Sect. VII-E): camera pixel (x, y) of a W×H image takes
 * its s×s fine pixels, each one's ray from the affine view tangents (t0 + col·dt, r0 + row·dr:
 * Camera.tangent_steps), its direction cosines (α, β) = −(t_x, t_y)/√(1 + t_x² + t_y²) and its
 * bins (u, v) = (α − ca, β − cb)·bin2, read with the ES kernel in each of the PLANES spectra A
 * (h, w each; the looks' LOOK_PLANES channels, look after look) times its scale. Out: each
 * plane's mean |A|² (power, (PLANES, H, W)), each look's mean u1·conj(u2) (cross, (looks, H,
 * W)) with u1 the sum of the channels in the bit mask SAME and u2 channel PARTNER (−1: none),
 * and with KEEP_FINE the fine images themselves (fine, (PLANES, H·s, W·s)). */
#ifdef LOOK_PLANES
#define LOOKS (PLANES / LOOK_PLANES)
__kernel void read_folded(__global float *power, __global float2 *cross, __global float2 *fine,
                          __global const float2 *A, int h, int w, int W, int H, int s, real t0,
                          real dt, real r0, real dr, real ca, real cb, real bin2,
                          __global const float *scale, __global const float2 *es)
{
    int x = get_global_id(0), y = get_global_id(1);
    float pw[PLANES];
    float2 cr[LOOKS];
    for (int p = 0; p < PLANES; p++)
        pw[p] = 0.0f;
    for (int l = 0; l < LOOKS; l++)
        cr[l] = 0.0f;
    for (int i = 0; i < s; i++)
    for (int j = 0; j < s; j++) {
        int row = y * s + i, col = x * s + j;
        real tx = t0 + col * dt, ty = r0 + row * dr, n = sqrt(tx * tx + ty * ty + 1);
        real u = (-tx / n - ca) * bin2, v = (-ty / n - cb) * bin2;
        int u0 = (int)floor(u) - TAPS / 2 + 1, v0 = (int)floor(v) - TAPS / 2 + 1;
        float fu = (float)(u - u0), fv = (float)(v - v0), wu[TAPS];
        for (int du = 0; du < TAPS; du++)
            wu[du] = es_weight(es, fu - du);
        float2 a[PLANES];
        for (int p = 0; p < PLANES; p++)
            a[p] = 0.0f;
        for (int dv = 0; dv < TAPS; dv++) {
            int m = v0 + dv;
            if (m < -(h / 2) || m > (h - 1) / 2)
                continue;
            float wv = es_weight(es, fv - dv);
            size_t at = (size_t)(m < 0 ? m + h : m) * w;
            for (int du = 0; du < TAPS; du++) {
                int k = u0 + du;
                if (k < -(w / 2) || k > (w - 1) / 2)
                    continue;
                float wgt = wv * wu[du];
                size_t here = at + (k < 0 ? k + w : k);
                for (int p = 0; p < PLANES; p++)
                    a[p] += wgt * A[(size_t)p * h * w + here];
            }
        }
        for (int p = 0; p < PLANES; p++) {
            a[p] *= scale[p];
            pw[p] += dot(a[p], a[p]);
#if KEEP_FINE
            fine[((size_t)p * H * s + row) * W * s + col] = a[p];
#endif
        }
#if PARTNER >= 0
        for (int l = 0; l < LOOKS; l++) {
            float2 u1 = 0.0f;
            for (int c = 0; c < LOOK_PLANES; c++)
                if (SAME >> c & 1)
                    u1 += a[l * LOOK_PLANES + c];
            cr[l] += cmul(u1, cconj(a[l * LOOK_PLANES + PARTNER]));
        }
#endif
    }
    float mean = 1.0f / (s * s);
    for (int p = 0; p < PLANES; p++)
        power[((size_t)p * H + y) * W + x] = pw[p] * mean;
    for (int l = 0; l < LOOKS; l++)
        cross[((size_t)l * H + y) * W + x] = cr[l] * mean;
}
#endif
