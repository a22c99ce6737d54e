/* The spectrum rotation of tilt.py. */
#include "spectrum_read.h"

#ifdef TAPS
/* Spectrum rotation (Eq. 11): the target spectrum at frequency (fξ, fη) of its (ht, wt) grid
 * is the source spectrum at f = M·(fξ, fη, fζ), times the Jacobian |∂(fx,fy)/∂(fξ,fη)|;
 * waves travelling backwards in either frame are dropped. m: row-major M (target -> source
 * axes). dft, dfs: frequency steps (row, col) of target and source; c*: centre (row, col)
 * indices over the grid size, of the target (A comes centred); scale: sample areas and the
 * inverse FFT's 1/N. Global size: by_rows of (ht, wt). Options: -DTAPS=<n>,
 * -DES_TABLE=<entries>. */
__kernel void rotate_spectrum(__global float2 *dst, __global const float2 *A, int hs, int ws,
                              int ht, int wt, real dft_y, real dft_x, real dfs_y, real dfs_x,
                              real inv_l2, real m00, real m01, real m02, real m10, real m11,
                              real m12, real m20, real m21, real m22, real ct_y, real ct_x,
                              float scale, __global const float2 *es)
{
    int j = get_global_id(0), i = get_global_id(1);
    if (j >= wt)
        return;
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
