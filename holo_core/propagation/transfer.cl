/* Transfer functions made on the device, on the padded (h, w) grid in FFT order, times
 * ``scale`` (the inverse FFT's 1/(h·w)). Global size (w, h) (below).
 *
 * Angular spectrum (Eq. 12-15): exp(i(c - z·g + 2π(fx·x0 + fy·y0))), g = 2π·f²/(1/λ + fz), the
 * carrier c = 2πz/λ mod 2π folded on the host in float64; evanescent waves dropped; with
 * ``band`` the shifted band limit rolled off by a raised cosine over the outer ``edge`` of
 * the rays' range (angular_spectrum.py). Fresnel: exp(i(c - πλz·f² + 2π(fx·x0 + fy·y0))),
 * the rays x0 - λz·fx kept inside half the window.
 *
 * With HOLO_FP64 the phase can be formed and reduced in double. The chirp route needs no
 * double: the per-frequency chirp g comes in as two floats (g = hi + lo, made in float64 on
 * the host once per grid and wavelength), z as two floats, and z·g is formed by an error-free
 * product (fma) and reduced by a three-part 2π: exact to float32 at any k·z. The offset enters
 * as two vectors of exp(i2π·f·x0) made in float64 on the host.
 *
 * Global size (w, h): consecutive work items write consecutive samples of a row (CPU
 * runtimes vectorise along the first dimension, GPUs coalesce along it). */
#include "holo_complex.h"
#include "fft_order.h"

#define TWO_PI_1 6.28318548202514648f      /* float(2π) */
#define TWO_PI_2 -1.74845553146951715e-07f   /* float(2π - TWO_PI_1) */
#define TWO_PI_3 -7.10542735760100186e-15f   /* float(the rest) */

/* cos² roll-off of a ray landing at u (1: the window's edge): branch-free arithmetic (HOLO_CIS,
 * not cospi), which CPU runtimes vectorise */
inline float roll_off(float u, float edge)
{
    float x = 1.57079633f * clamp((u - (1.0f - edge)) / edge, 0.0f, 1.0f), c, s;
    HOLO_CIS(float, x, c, s);
    return u <= 1.0f ? c * c : 0.0f;
}

#ifdef HOLO_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable

__kernel void asm_transfer(__global float2 *t, double dfy, double dfx, double inv_l, double z,
                           double c, double x0, double y0, double half_y, double half_x,
                           int band, float edge, float scale)
{
    int j = get_global_id(0), i = get_global_id(1), w = get_global_size(0), h = get_global_size(1);
    double fy = signed_index(i, h) * dfy, fx = signed_index(j, w) * dfx;
    double f2 = fx * fx + fy * fy, fz2 = inv_l * inv_l - f2;
    float2 v = (float2)(0.0f, 0.0f);
    if (fz2 > 0) {
        double fz = sqrt(fz2);
        double ph = c - 2 * M_PI * z * f2 / (inv_l + fz) + 2 * M_PI * (fx * x0 + fy * y0);
        ph -= 2 * M_PI * rint(ph / (2 * M_PI));
        float weight = 1.0f;
        if (band)
            weight = roll_off((float)(fabs(x0 - z * fx / fz) / half_x), edge)
                   * roll_off((float)(fabs(y0 - z * fy / fz) / half_y), edge);
        v = (scale * weight) * cexpi((float)ph);
    }
    t[i * w + j] = v;
}

/* with ``quadrant`` (no offset) only the first quadrant, as asm_transfer_chirp makes it (gw
 * samples a row, the global size rounded up) */
__kernel void fresnel_transfer(__global float2 *t, int quadrant, int h, int w, int gw,
                               double dfy, double dfx, double lam, double z, double c,
                               double x0, double y0, double half_y, double half_x, float scale)
{
    int j = get_global_id(0), i = get_global_id(1);
    if (j >= gw)
        return;
    double fy = (quadrant ? i : signed_index(i, h)) * dfy;
    double fx = (quadrant ? j : signed_index(j, w)) * dfx;
    float2 v = (float2)(0.0f, 0.0f);
    if (fabs(x0 - lam * z * fx) <= half_x && fabs(y0 - lam * z * fy) <= half_y) {
        double ph = c - M_PI * lam * z * (fx * fx + fy * fy) + 2 * M_PI * (fx * x0 + fy * y0);
        ph -= 2 * M_PI * rint(ph / (2 * M_PI));
        v = scale * cexpi((float)ph);
    }
    t[i * gw + j] = v;
}
#endif

/* z·(hi + lo) mod 2π in float, z = z_hi + z_lo: the product's rounding error recovered by fma */
inline float product_mod_2pi(float z_hi, float z_lo, float hi, float lo)
{
    float p = z_hi * hi;
    float e = fma(z_hi, hi, -p) + z_hi * lo + z_lo * hi;
    float n = rint(p * 0.159154943f);
    float r = fma(-n, TWO_PI_1, p);
    r = fma(-n, TWO_PI_2, r);
    r = fma(-n, TWO_PI_3, r);
    return r + e;
}

/* The angular spectrum from its chirp table, made once per (grid, λ, pitch): per |signed
 * index| (row, column) of the grid's first quadrant ((h/2 + 1) x qw), g = (g_hi, g_lo) and
 * 1/fz, 1/fz < 0 where the wave is evanescent (g and fz depend on fx² and fy² only; two
 * arrays, not a float4, which CPU runtimes vectorise poorly). rx, ry:
 * exp(i2π·f·x0) per column and row, read where ``shifted``; the band's rays x0 - z·fx/fz in
 * float (the band needs 1e-3). One pass over the grid, no square root or division. With
 * ``quadrant`` (no offset: the function is even in fx and fy) only the first quadrant is
 * made: t of (h/2 + 1, w/2 + 1). Global size (gw rounded up, rows of t): items beyond the
 * row's gw samples do nothing (a CPU runtime vectorises only a work group of whole lanes). */
__kernel void asm_transfer_chirp(__global float2 *t, __global const float2 *g,
                                 __global const float *inv_fz, int qw,
                                 __global const float2 *ry, __global const float2 *rx,
                                 int shifted, int quadrant, int h, int w, int gw, float z_hi,
                                 float z_lo, float c, float dfy, float dfx, float x0, float y0,
                                 float half_y, float half_x, int band, float edge, float scale)
{
    int j = get_global_id(0), i = get_global_id(1);
    if (j >= gw)
        return;
    int si = quadrant ? i : signed_index(i, h), sj = quadrant ? j : signed_index(j, w);
    int k = abs(si) * qw + abs(sj);
    float2 e = g[k];
    float r = inv_fz[k];
    float2 v = (float2)(0.0f, 0.0f);
    if (r >= 0) {
        float ph = c - product_mod_2pi(z_hi, z_lo, e.x, e.y);
        float weight = 1.0f;
        if (band) {
            float z = z_hi + z_lo;
            weight = roll_off(fabs(x0 - z * (sj * dfx) * r) / half_x, edge)
                   * roll_off(fabs(y0 - z * (si * dfy) * r) / half_y, edge);
        }
        v = (scale * weight) * cexpi(ph);
        if (shifted)
            v = cmul(v, cmul(ry[i], rx[j]));
    }
    t[i * gw + j] = v;
}
