/* Camera holograms (camera_hologram.py): emitters into a depth layer's spectrum, layers onto
 * the pupil, the pupil through the lens, its image read at the pixels. Arrays are in FFT order:
 * sample (row r, col c) of an (h, w) grid lies at signed index (r or r - h, c or c - w). */
#include "spectrum_read.h"

inline int signed_index(int i, int n) { return i <= (n - 1) / 2 ? i : i - n; }

/* S[idx[i]] = amp[i]·exp(i(phase0[i] + phi[i])) for the emitters i = first + global id: one
 * emitter per spectrum bin, its plane wave's direction; phase0 = k·R mod 2π (folded on the
 * host in float64), phi its random phase of this look. */
__kernel void scatter(__global float2 *S, __global const int *idx, __global const float *amp,
                      __global const float *phase0, __global const float *phi, int first)
{
    int i = first + get_global_id(0);
    S[idx[i]] = amp[i] * cexpi(phase0[i] + phi[i]);
}

/* P += u·exp(ik(√(ρ² + z²) − z)): one layer's plane waves given the spherical curvature of
 * its distance z [m] (the Fresnel approximation per layer); (dy, dx) the pupil's pitch [m].
 * Global size (h, w). */
__kernel void add_layer(__global float2 *P, __global const float2 *u, float dy, float dx,
                        float k, float z)
{
    int r = get_global_id(0), c = get_global_id(1), w = get_global_size(1);
    float y = signed_index(r, get_global_size(0)) * dy, x = signed_index(c, w) * dx;
    float rho2 = x * x + y * y;
    P[r * w + c] += cmul(u[r * w + c], cexpi(k * rho2 / (sqrt(rho2 + z * z) + z)));
}

/* Q (2h, 2w, zeroed) at the pupil's samples: P·w(ρ)·exp(−ik(√(ρ² + f²) − f))·d(x)·d(y), the
 * iris w (1 inside (1 − taper)·radius, a raised cosine to 0 at the radius [m]), the thin lens
 * of Eq. 24 focused at f [m] (f = 0: none), and the deapodization d of the ES read that
 * follows. Global size (h, w) of P. */
__kernel void pupil_window(__global float2 *Q, __global const float2 *P, float dy, float dx,
                           float radius, float taper, float k, float f,
                           __global const float *dy_apod, __global const float *dx_apod)
{
    int r = get_global_id(0), c = get_global_id(1), h = get_global_size(0), w = get_global_size(1);
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

/* The incoherent route (incoherent.py), on the pupil's 2x padded spectrum grid (H, W). */

/* M[idx[i]] = val[i]: one emitter per bin, its complex weight. */
__kernel void scatter_values(__global float2 *M, __global const int *idx,
                             __global const float2 *val, int first)
{
    int i = first + get_global_id(0);
    M[idx[i]] = val[i];
}

/* From a layer's coherent point spread functions p1 (λ1) and p2 (λ2): p1 ← |p1|², the
 * intensity PSF, and p2 ← p1·conj(p2), the depth pair's cross PSF. */
__kernel void psf_products(__global float2 *p1, __global float2 *p2)
{
    int i = get_global_id(0);
    float2 a = p1[i], b = p2[i];
    p2[i] = cmul(a, (float2)(b.x, -b.y));
    p1[i] = (float2)(a.x * a.x + a.y * a.y, 0.0f);
}

/* acc += m·k: a layer's emitter map times its PSF's transfer function. */
__kernel void multiply_add(__global float2 *acc, __global const float2 *m,
                           __global const float2 *k)
{
    int i = get_global_id(0);
    acc[i] += cmul(m[i], k[i]);
}

/* Q (zeroed, FFT order) ← A·ay[r]·ax[c] at the same signed indices: the images' spectra
 * (h, w) padded into a larger grid and deapodized for the ES read that follows. Global size
 * (h, w) of A. */
__kernel void embed_deapodized(__global float2 *Q, int H, int W, __global const float2 *A,
                               __global const float *ay, __global const float *ax)
{
    int r = get_global_id(0), c = get_global_id(1), h = get_global_size(0), w = get_global_size(1);
    int sr = signed_index(r, h), sc = signed_index(c, w);
    Q[(sr < 0 ? sr + H : sr) * W + (sc < 0 ? sc + W : sc)] = (ay[r] * ax[c]) * A[r * w + c];
}
