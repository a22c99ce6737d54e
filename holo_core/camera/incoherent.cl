/* The incoherent route (incoherent.py), on the pupil's 2x padded spectrum grid (H, W), in FFT
 * order. */
#include "holo_complex.h"
#include "fft_order.h"

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

/* acc = m'·k (``first``) or acc + m'·k on the (2h, 2w) grid: a layer's emitter map times its
 * PSF's transfer function. The map holds emitters only at even bins of that grid, so its
 * transform there is m (the transform of the (h, w) map) tiled 2 x 2: m' at (r, c) is m at
 * (r mod h, c mod w). Global size: by_rows of (2h, 2w). */
__kernel void multiply_tiled(__global float2 *acc, __global const float2 *m,
                             __global const float2 *k, int h, int w, int first)
{
    int c = get_global_id(0), r = get_global_id(1), W = 2 * w;
    if (c >= W)
        return;
    int i = r * W + c;
    float2 v = cmul(m[(r < h ? r : r - h) * w + (c < w ? c : c - w)], k[i]);
    acc[i] = first ? v : acc[i] + v;
}

/* Q (FFT order) ← A·ay[r]·ax[c] at the same signed indices: the images' spectra (h, w) padded
 * into a larger grid (H, W) and deapodized for the ES read that follows; the rest of Q is left
 * as it is (the FFT takes it as zero). Global size: by_rows of (h, w). */
__kernel void embed_deapodized(__global float2 *Q, int H, int W, __global const float2 *A,
                               int h, int w, __global const float *ay,
                               __global const float *ax)
{
    int c = get_global_id(0), r = get_global_id(1);
    if (c >= w)
        return;
    int sr = signed_index(r, h), sc = signed_index(c, w);
    Q[(sr < 0 ? sr + H : sr) * W + (sc < 0 ? sc + W : sc)] = (ay[r] * ax[c]) * A[r * w + c];
}
