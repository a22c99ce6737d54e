/* A carrier plate's light towards one pupil (plate/to_pupil.py), up to its decimated samples
 * (plate/gather.cl sums them onto the pupil's plane waves).
 *
 * demodulate_decimate: B(x)·exp(ik(|x - P| - |x - Z|)), the samples against the carrier
 *     converging on the pupil's centre P instead of the zone's centre Z, low-passed along
 *     each row and thinned to every Q-th column; decimate then does the same along columns.
 *     The phase is exact at each segment's centre (demodulate_centres: the distances'
 *     difference (P - Z)·(P + Z - 2x) / (|x - P| + |x - Z|) in REAL, double where the device
 *     has it, reduced) and follows in float from there. The low-pass (TAPS taps h) filters
 *     off the light that leaves towards other parts of the zone before the samples thin out
 *     to what the pupil sees.
 */
#include "holo_complex.h"

#ifndef TAPS        /* each kernel's options define what it uses */
#define TAPS 1
#endif
#define SEGMENT 32   /* columns per exact phase (demodulate_centres) */
#ifndef PLANES
#define PLANES 1
#define GROUP 1
#define Q 1
#endif

#include "real.h"

/* the phase k(|x - P| - |x - Z|) at the centre of each segment of SEGMENT columns of each row,
 * formed in REAL and reduced: what demodulate adds its float differences to */
__kernel void demodulate_centres(__global float *table, int rows, int segments, real pitch,
                                 real row_pitch, real x0, real y0, real k, real px, real py,
                                 real pz, real zx, real zy, real zz)
{
    int s = get_global_id(0), r = get_global_id(1);
    if (r >= rows || s >= segments)
        return;
    real x = x0 + (s * SEGMENT + SEGMENT / 2) * pitch, y = y0 + r * row_pitch;
    real ax = px - x, ay = py - y, bx = zx - x, by = zy - y;
    real to_p = sqrt(ax * ax + ay * ay + pz * pz), to_z = sqrt(bx * bx + by * by + zz * zz);
    real num = (px - zx) * (px + zx - 2 * x) + (py - zy) * (py + zy - 2 * y) + (pz - zz) * (pz + zz);
    real ph = k * num / (to_p + to_z);
    table[r * segments + s] = (float)(ph - (real)(2 * M_PI) * rint(ph * (real)(0.5 / M_PI)));
}

/* exp(ik(|x - P| - |x - Z|)) at column c of row r: the segment centre's phase (table) plus,
 * in float, the change of each distance from there: |x - A| - |x_c - A| =
 * dx·(a + a_c)/(|x - A| + |x_c - A|) with a = x - A_x, a_c = a - dx (y and z held) */
inline float2 turn_towards_pupil(int c, int r, real pitch, real row_pitch, real x0, real y0,
                                 float k, real px, real py, real pz, real zx, real zy, real zz,
                                 __global const float *table, int segments)
{
    int s = c / SEGMENT;
    float dx = (float)((c - (s * SEGMENT + SEGMENT / 2)) * pitch);
    real x = x0 + c * pitch, y = y0 + r * row_pitch;
    float ax = (float)(x - px), ay = (float)(y - py), bx = (float)(x - zx), by = (float)(y - zy);
    float pz2 = (float)(pz * pz), zz2 = (float)(zz * zz);
    float axc = ax - dx, bxc = bx - dx;
    float rp = sqrt(ax * ax + ay * ay + pz2), rpc = sqrt(axc * axc + ay * ay + pz2);
    float rz = sqrt(bx * bx + by * by + zz2), rzc = sqrt(bxc * bxc + by * by + zz2);
    float change = dx * ((ax + axc) / (rp + rpc) - (bx + bxc) / (rz + rzc));
    return cexpi(table[r * segments + s] + k * change);
}

/* Turned onto the pupil's carrier (turn_towards_pupil) and decimated along the row at once: a
 * work group of GROUP outputs of one row loads the GROUP·Q + TAPS samples they read into local
 * memory, each turned once, then each output sums its TAPS taps h there. The input's column 0
 * is the plate's column col0 (its x is x0); output j reads input Q·j + lead + t. The input's
 * sample (p, r, c) is samples[first + p·plane + r·stride + c]: a band copied to the device, or
 * the host's whole array read in place. */
__kernel void demodulate_decimate(__global float2 *out, __global const float2 *samples,
                                  long first, long plane, int stride, int rows, int cols,
                                  int out_cols, int out_row0, int out_height, int lead,
                                  __constant float *h, real pitch, real row_pitch,
                                  real x0, real y0, float k, real px, real py, real pz,
                                  real zx, real zy, real zz, __global const float *table,
                                  int segments)
{
    /* polyphase order: input i at (i % Q)·PHASE + i / Q, so that the outputs of a group
     * read their taps from neighbouring places (the vector lanes of a CPU load together) */
#define PHASE (GROUP + (TAPS + Q - 1) / Q + 1)
    __local float2 span[PLANES][Q * PHASE];
    int lid = get_local_id(0), j0 = get_group_id(0) * GROUP, r = get_global_id(1);
    int start = Q * j0 + lead;
    /* item lid stages inputs lid·Q + ph, at ph·PHASE + lid: the lanes store side by side;
     * then the TAPS inputs past the group's, item by item */
    for (int n = 0; n < Q + (TAPS + GROUP - 1) / GROUP; n++) {
        int i = n < Q ? lid * Q + n : GROUP * Q + (n - Q) * GROUP + lid;
        if (i >= GROUP * Q + TAPS)
            continue;
        int c = start + i;
        float2 turn = 0;
        if (c >= 0 && c < cols)
            turn = turn_towards_pupil(c, r, pitch, row_pitch, x0, y0, k, px, py, pz, zx, zy,
                                      zz, table, segments);
        int at = n < Q ? n * PHASE + lid : (i % Q) * PHASE + i / Q;
        for (int p = 0; p < PLANES; p++)
            span[p][at] = c >= 0 && c < cols
                ? cmul(samples[first + p * plane + (long)r * stride + c], turn) : (float2)0;
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    int j = j0 + lid;
    if (j >= out_cols)
        return;
    for (int p = 0; p < PLANES; p++) {
        float2 acc = 0;
        for (int ph = 0; ph < Q; ph++)       /* tap t = ph + Q·m */
            for (int m = 0; ph + Q * m < TAPS; m++)
                acc += h[ph + Q * m] * span[p][ph * PHASE + lid + m];
        out[((long)p * out_height + out_row0 + r) * out_cols + j] = acc;
    }
}

/* along rows: the input (planes, rows, cols); output row i reads input row q·i + first + t.
 * Output (i, c) of each plane goes to out[slot[i·cols + c]·stride + plane0 + plane]: the
 * spread's order, every plane of a sample side by side (it reads them together). */
__kernel void decimate(__global float2 *out, __global const float2 *rowpass, int rows,
                       int cols, int out_rows, __global const int *slot, int stride,
                       int plane0, int q, int first, __constant float *h)
{
    int c = get_global_id(0), r = get_global_id(1), plane = get_global_id(2);
    if (r >= out_rows || c >= cols)
        return;
    __global const float2 *src = rowpass + (long)plane * rows * cols;
    float2 acc = 0;
    int start = q * r + first;
    for (int t = 0; t < TAPS; t++) {
        int i = start + t;
        if (i >= 0 && i < rows)
            acc += h[t] * src[(long)i * cols + c];
    }
    out[(long)slot[r * cols + c] * stride + plane0 + plane] = acc;
}
