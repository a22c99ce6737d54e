/* Element-wise stages of spectral propagation. */
#include "holo_complex.h"

/* a *= t, element-wise. */
__kernel void multiply(__global float2 *a, __global const float2 *t)
{
    int i = get_global_id(0);
    a[i] = cmul(a[i], t[i]);
}
