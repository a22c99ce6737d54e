/* Direct Rayleigh-Sommerfeld integration (Eq. 7), one work item per output sample.
 * The impulse response of the first kind, h = z/(2π r²)·(1/r - ik)·exp(ikr), is exactly the
 * inverse transform of the angular spectrum's exp(i2πz·fz). Its carrier exp(ik|z|) and the
 * sample area are applied as one float64 factor `g` from the host; the kernel forms
 * k(r - |z|) = k·ρ²/(r + |z|), which stays small. REAL is double where the device has it. */
#include "holo_complex.h"

#include "real.h"

__kernel void rs_direct(__global float2 *out, __global const float2 *src,
                        int h, int w, real pitch, real src_x0, real src_y0,
                        real out_pitch, real out_x0, real out_y0,
                        real z, real k, real sgn, real gr, real gi)
{
    int i = get_global_id(0), j = get_global_id(1), out_w = get_global_size(1);
    real xo = out_x0 + j * out_pitch, yo = out_y0 + i * out_pitch;
    real z2 = z * z, c2pi = z / (2 * M_PI);
    real acc_r = 0, acc_i = 0;
    for (int a = 0; a < h; a++) {
        real dy = yo - (src_y0 + a * pitch);
        for (int b = 0; b < w; b++) {
            float2 u = src[a * w + b];
            if (u.x == 0.0f && u.y == 0.0f)
                continue;
            real dx = xo - (src_x0 + b * pitch);
            real rho2 = dx * dx + dy * dy, r = sqrt(rho2 + z2);
            real c, s = sincos(sgn * k * rho2 / (r + z), &c);
            real ar = c2pi / (r * r * r), ai = -sgn * c2pi * k / (r * r);
            real hr = ar * c - ai * s, hi = ar * s + ai * c;
            acc_r += u.x * hr - u.y * hi;
            acc_i += u.x * hi + u.y * hr;
        }
    }
    out[i * out_w + j] = (float2)(acc_r * gr - acc_i * gi, acc_r * gi + acc_i * gr);
}
