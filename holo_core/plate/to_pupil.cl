/* A carrier plate's light towards one pupil (plate/to_pupil.py).
 *
 * demodulate: B(x)·exp(ik(|x - P| - |x - Z|)) in place: the samples against the carrier
 *     converging on the pupil's centre P instead of the zone's centre Z. The phase's distance
 *     difference is formed as (P - Z)·(P + Z - 2x) / (|x - P| + |x - Z|) in REAL (double where
 *     the device has it), then reduced.
 * decimate: a low-pass FIR over one axis and every q-th sample (TAPS taps h, the output's
 *     sample n at input q·n + first + t): the light that leaves towards other parts of the zone
 *     is filtered off before the samples thin out to what the pupil sees.
 * spread: the type-1 non-uniform FFT's gather: each point (row, col) of the 2× oversampled
 *     spectrum grid sums the samples within ES_TAPS/2 of it (their grid coordinates gy, gx),
 *     weighted by the ES kernel (its table es: value and slope per interval), finding them in
 *     the cells of the grid they are listed by.
 */
#include "holo_complex.h"

#ifndef TAPS        /* each kernel's options define what it uses */
#define TAPS 1
#endif
#ifndef CHANNELS
#define CHANNELS 1
#endif
#ifndef ES_TAPS
#define ES_TAPS 6
#define ES_TABLE 4096
#endif
#ifndef CELL
#define CELL 3
#endif

#ifdef HOLO_FP64
typedef double real;
#else
typedef float real;
#endif

__kernel void demodulate(__global float2 *b, int planes, int rows, int cols, real pitch,
                         real row_pitch, real x0, real y0, real k, real px, real py, real pz, real zx, real zy,
                         real zz)
{
    int r = get_global_id(0), c = get_global_id(1);
    if (r >= rows || c >= cols)
        return;
    real x = x0 + c * pitch, y = y0 + r * row_pitch;
    real ax = px - x, ay = py - y, bx = zx - x, by = zy - y;
    real to_p = sqrt(ax * ax + ay * ay + pz * pz), to_z = sqrt(bx * bx + by * by + zz * zz);
    real num = (px - zx) * (px + zx - 2 * x) + (py - zy) * (py + zy - 2 * y) + (pz - zz) * (pz + zz);
    real ph = k * num / (to_p + to_z);
    ph -= (real)(2 * M_PI) * rint(ph * (real)(0.5 / M_PI));
    float2 turn = cexpi((float)ph);
    for (int plane = 0; plane < planes; plane++) {
        long i = ((long)plane * rows + r) * cols + c;
        b[i] = cmul(b[i], turn);
    }
}

/* along columns (axis 1) when ALONG_COLS, else along rows; the input (planes, rows, cols),
 * the output's rows from out_row0 of (planes, out_height, out_cols), out_rows of them */
__kernel void decimate(__global float2 *out, __global const float2 *in, int rows, int cols,
                       int out_rows, int out_cols, int out_row0, int out_height, int q,
                       int first, __constant float *h)
{
    int r = get_global_id(0), c = get_global_id(1), plane = get_global_id(2);
    if (r >= out_rows || c >= out_cols)
        return;
    __global const float2 *src = in + (long)plane * rows * cols;
    float2 acc = 0;
#ifdef ALONG_COLS
    int start = q * c + first;
    for (int t = 0; t < TAPS; t++) {
        int j = start + t;
        if (j >= 0 && j < cols)
            acc += h[t] * src[(long)r * cols + j];
    }
#else
    int start = q * r + first;
    for (int t = 0; t < TAPS; t++) {
        int i = start + t;
        if (i >= 0 && i < rows)
            acc += h[t] * src[(long)i * cols + c];
    }
#endif
    out[((long)plane * out_height + out_row0 + r) * out_cols + c] = acc;
}

inline float es_weight(float t, __constant float2 *es)
{
    float u = (t + 0.5f * ES_TAPS) * (ES_TABLE / (float)ES_TAPS);
    if (u <= 0 || u >= ES_TABLE)
        return 0;
    int i = (int)u;
    float2 e = es[i];
    return e.x + (u - i) * e.y;
}

/* out (CHANNELS, grid_h, grid_w) FFT order over the launched block of signed grid
 * coordinates from (row_first, col_first): the samples within ES_TAPS/2 of each point. The
 * samples are listed by cells of CELL x CELL grid units from (row_first, col_first) (cell c's
 * in [start[c], start[c + 1]), cells_w a row): their grid coordinates gy, gx, weights wt and
 * their index n into the values v (CHANNELS, count) */
__kernel void spread(__global float2 *out, int grid_h, int grid_w, int row_first,
                     int col_first, __global const float2 *v, int count,
                     __global const float *wt, __global const float *gy,
                     __global const float *gx, __global const int *index,
                     __global const int *start, int cells_h, int cells_w, float scale,
                     __constant float2 *es)
{
    int gr_i = row_first + get_global_id(0), gc_i = col_first + get_global_id(1);
    float gr = gr_i, gc = gc_i;                          /* signed grid coordinates */
    int row = gr_i < 0 ? gr_i + grid_h : gr_i, col = gc_i < 0 ? gc_i + grid_w : gc_i;
    int ci0 = max((int)floor((gr - 0.5f * ES_TAPS - row_first) / CELL), 0);
    int ci1 = min((int)floor((gr + 0.5f * ES_TAPS - row_first) / CELL), cells_h - 1);
    int cj0 = max((int)floor((gc - 0.5f * ES_TAPS - col_first) / CELL), 0);
    int cj1 = min((int)floor((gc + 0.5f * ES_TAPS - col_first) / CELL), cells_w - 1);
    float2 sum[CHANNELS];
    for (int ch = 0; ch < CHANNELS; ch++)
        sum[ch] = 0;
    for (int ci = ci0; ci <= ci1; ci++)
    for (int cj = cj0; cj <= cj1; cj++)
    for (int m = start[ci * cells_w + cj], m1 = start[ci * cells_w + cj + 1]; m < m1; m++) {
        float dy = gy[m] - gr, dx = gx[m] - gc;
        if (fabs(dy) >= 0.5f * ES_TAPS || fabs(dx) >= 0.5f * ES_TAPS)
            continue;
        float w = scale * wt[m] * es_weight(dy, es) * es_weight(dx, es);
        int n = index[m];
        for (int ch = 0; ch < CHANNELS; ch++)
            sum[ch] += w * v[(long)ch * count + n];
    }
    for (int ch = 0; ch < CHANNELS; ch++)
        out[((long)ch * grid_h + row) * grid_w + col] = sum[ch];
}

/* U (CHANNELS, h, w) += the (2h, 2w) grid's transform at the pupil's samples (FFT order),
 * deapodized (1 / (dr·dc)), times the layer's curvature exp(ik(√(ρ² + z²) - z)) */
__kernel void pupil_layer(__global float2 *u, __global const float2 *g, int h, int w,
                          __global const float *dr, __global const float *dc, float dy,
                          float dx, float k, float z)
{
    int r = get_global_id(0), c = get_global_id(1), ch = get_global_id(2);
    int sr = r < (h + 1) / 2 ? r : r - h, sc = c < (w + 1) / 2 ? c : c - w;
    int gr = sr < 0 ? sr + 2 * h : sr, gc = sc < 0 ? sc + 2 * w : sc;
    float y = sr * dy, x = sc * dx, rho2 = x * x + y * y;
    float curve = k * rho2 / (sqrt(rho2 + z * z) + z);
    float2 val = g[((long)ch * 2 * h + gr) * 2 * w + gc] * (1.0f / (dr[r] * dc[c]));
    u[((long)ch * h + r) * w + c] += cmul(val, cexpi(curve));
}
