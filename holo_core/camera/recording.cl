/* Camera holograms (recording.py): emitters into a depth layer's spectrum, layers onto the
 * pupil. Arrays are in FFT order: sample (row r, col c) of an (h, w) grid lies at signed index
 * (r or r - h, c or c - w). */
#include "holo_complex.h"
#include "fft_order.h"

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
 * Global size: by_rows of (h, w). */
__kernel void add_layer(__global float2 *P, __global const float2 *u, int h, int w, float dy,
                        float dx, float k, float z)
{
    int c = get_global_id(0), r = get_global_id(1);
    if (c >= w)
        return;
    float y = signed_index(r, h) * dy, x = signed_index(c, w) * dx;
    float rho2 = x * x + y * y;
    P[r * w + c] += cmul(u[r * w + c], cexpi(k * rho2 / (sqrt(rho2 + z * z) + z)));
}
