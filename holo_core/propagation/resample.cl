/* Band-limited resampling (resample.py). */
#include "holo_complex.h"

/* One axis of band-limited resampling: out = K · src along rows (axis 0) or columns (axis 1).
 * K is (n_out, n_in), real. Global size = out shape. */
__kernel void apply_axis0(__global float2 *out, __global const float *K,
                          __global const float2 *src, int n_in)
{
    int i = get_global_id(0), c = get_global_id(1), w = get_global_size(1);
    float2 acc = (float2)(0.0f, 0.0f);
    for (int a = 0; a < n_in; a++)
        acc += K[i * n_in + a] * src[a * w + c];
    out[i * w + c] = acc;
}

__kernel void apply_axis1(__global float2 *out, __global const float *K,
                          __global const float2 *src, int n_in)
{
    int r = get_global_id(0), j = get_global_id(1), w = get_global_size(1);
    float2 acc = (float2)(0.0f, 0.0f);
    for (int b = 0; b < n_in; b++)
        acc += K[j * n_in + b] * src[r * n_in + b];
    out[r * w + j] = acc;
}
