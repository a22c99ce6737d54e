/* Element-wise stages of spectral propagation (convolution.py). */
#include "holo_complex.h"

/* a *= t, element-wise. */
__kernel void multiply(__global float2 *a, __global const float2 *t)
{
    int i = get_global_id(0);
    a[i] = cmul(a[i], t[i]);
}

/* t = w·exp(i(c - d·g)) with (w, g) packed in wg: a transfer function exp(i2πd·fz) whose
 * chirp g = 2πf²/(1/λ + fz) [rad/m] is shared by every distance d (wavefront recording planes) */
__kernel void chirp_transfer(__global float2 *t, __global const float2 *wg, float c, float d)
{
    int i = get_global_id(0);
    float2 v = wg[i];
    t[i] = v.x * cexpi(c - d * v.y);
}
