/* A carrier plate's decimated samples summed onto the plane waves of a pupil
 * (plate/gather.py; plate/to_pupil.cl decimates them).
 *
 * spread: the type-1 non-uniform FFT's gather: each point (row, col) of the 2× oversampled
 *     spectrum grid sums the samples within ES_TAPS/2 of it (their grid coordinates gy, gx),
 *     weighted by the ES kernel (its table es: value and slope per interval), finding them in
 *     the cells of the grid they are listed by (a row of cells is one run of the list).
 */
#include "holo_complex.h"

#ifndef CHANNELS    /* each kernel's options define what it uses */
#define CHANNELS 1
#endif
#ifndef ES_TAPS
#define ES_TAPS 6
#define ES_TABLE 4096
#endif
#ifndef CELL
#define CELL 3
#endif

#include "real.h"

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
 * their values v (count, CHANNELS), in that order */
__kernel void spread(__global float2 *out, int grid_h, int grid_w, int row_first,
                     int col_first, __global const float2 *v, __global const float *wt,
                     __global const float *gy, __global const float *gx,
                     __global const int *start, int cells_h, int cells_w, float scale,
                     __constant float2 *es)
{
    int gc_i = col_first + get_global_id(0), gr_i = row_first + get_global_id(1);
    float gr = gr_i, gc = gc_i;                          /* signed grid coordinates */
    int row = gr_i < 0 ? gr_i + grid_h : gr_i, col = gc_i < 0 ? gc_i + grid_w : gc_i;
    int ci0 = max((int)floor((gr - 0.5f * ES_TAPS - row_first) / CELL), 0);
    int ci1 = min((int)floor((gr + 0.5f * ES_TAPS - row_first) / CELL), cells_h - 1);
    int cj0 = max((int)floor((gc - 0.5f * ES_TAPS - col_first) / CELL), 0);
    int cj1 = min((int)floor((gc + 0.5f * ES_TAPS - col_first) / CELL), cells_w - 1);
    float2 sum[CHANNELS];
    for (int ch = 0; ch < CHANNELS; ch++)
        sum[ch] = 0;
    for (int ci = ci0; ci <= ci1; ci++)  /* a row's cells cj0..cj1 are one run of the list */
    for (int m = start[ci * cells_w + cj0], m1 = start[ci * cells_w + cj1 + 1]; m < m1; m++) {
        float dy = gy[m] - gr, dx = gx[m] - gc;
        if (fabs(dy) >= 0.5f * ES_TAPS || fabs(dx) >= 0.5f * ES_TAPS)
            continue;
        float w = scale * wt[m] * es_weight(dy, es) * es_weight(dx, es);
        for (int ch = 0; ch < CHANNELS; ch++)
            sum[ch] += w * v[(long)m * CHANNELS + ch];
    }
    for (int ch = 0; ch < CHANNELS; ch++)
        out[((long)ch * grid_h + row) * grid_w + col] = sum[ch];
}

/* U (P, h, w) += the (2h, 2w) grid's transform at the pupil's samples (FFT order),
 * deapodized (1 / (dr·dc)), times the layer's curvature exp(ik(√(ρ² + z²) - z)) and scale,
 * for the n planes of one wavelength: plane pairs[i].x of U from plane pairs[i].y of the
 * grids (the curvature found once for all of them) */
__kernel void pupil_layer(__global float2 *u, __global const float2 *g, int h, int w,
                          __global const int2 *pairs, int n, __global const float *dr,
                          __global const float *dc, float dy, float dx, float k, float z,
                          float scale)
{
    int c = get_global_id(0), r = get_global_id(1);
    int sr = r < (h + 1) / 2 ? r : r - h, sc = c < (w + 1) / 2 ? c : c - w;
    int gr = sr < 0 ? sr + 2 * h : sr, gc = sc < 0 ? sc + 2 * w : sc;
    float y = sr * dy, x = sc * dx, rho2 = x * x + y * y;
    float curve = k * rho2 / (sqrt(rho2 + z * z) + z);
    float2 turn = cexpi(curve) * (scale / (dr[r] * dc[c]));
    for (int i = 0; i < n; i++) {
        int2 p = pairs[i];
        u[((long)p.x * h + r) * w + c] += cmul(g[((long)p.y * 2 * h + gr) * 2 * w + gc], turn);
    }
}

/* The gather's list, made on the device (_Gather in to_pupil.py): each decimated sample's
 * place on the spectrum grid, its weight and depth (gather_geometry), its cell (gather_keys,
 * counting each cell's samples), its place in the list: the cells in order, each cell's
 * samples by their index (gather_place, then gather_sort_cells: the atomic counter places a
 * cell's few samples in any order, the sort makes the list the same every time), and the
 * samples' values in the list's order (gather_permute). */

/* sample (i, j) at x = x0 + j·xs, y = y0 + i·ys on the plate: d = P - x; its direction's
 * cosines along the camera's axes (rot: the rotation's columns, row-major 3x3) less the
 * pupil's centre, in grid units (2/bin); weight w0/|d|² (Eq. 7 with the samples' area and
 * d_z); the inverse of its depth along the camera's axis */
__kernel void gather_geometry(__global float *gy, __global float *gx, __global float *wt,
                              __global float *inv_depth, int rows, int cols, real x0, real xs,
                              real y0, real ys, real px, real py, real pz,
                              __constant real *rot, real cy, real cx, real grid_units, real w0)
{
    int j = get_global_id(0), i = get_global_id(1);
    if (j >= cols || i >= rows)
        return;
    real dx = px - (x0 + j * xs), dy = py - (y0 + i * ys), dz = pz;
    real r2 = dx * dx + dy * dy + dz * dz, r = sqrt(r2);
    real a0 = dx * rot[0] + dy * rot[3] + dz * rot[6];
    real a1 = dx * rot[1] + dy * rot[4] + dz * rot[7];
    real a2 = dx * rot[2] + dy * rot[5] + dz * rot[8];
    long n = (long)i * cols + j;
    gx[n] = (float)(grid_units * (a0 / r - cx));
    gy[n] = (float)(grid_units * (a1 / r - cy));
    wt[n] = (float)(w0 / r2);
    inv_depth[n] = (float)(1 / a2);
}

/* each sample's cell (CELL grid units a side from (lo_y, lo_x), clipped to the cells_h x
 * cells_w box), and the count of each cell's samples */
__kernel void gather_keys(__global int *key, __global volatile int *count,
                          __global const float *gy, __global const float *gx, float lo_y,
                          float lo_x, int cells_h, int cells_w)
{
    int n = get_global_id(0);
    int ci = clamp((int)((gy[n] - lo_y) * (1.0f / CELL)), 0, cells_h - 1);
    int cj = clamp((int)((gx[n] - lo_x) * (1.0f / CELL)), 0, cells_w - 1);
    key[n] = ci * cells_w + cj;
    atomic_inc(count + ci * cells_w + cj);
}

__kernel void gather_place(__global int *order, __global volatile int *fill,
                           __global const int *key, __global const int *start)
{
    int n = get_global_id(0), k = key[n];
    order[start[k] + atomic_inc(fill + k)] = n;
}

__kernel void gather_sort_cells(__global int *order, __global const int *start)
{
    int c = get_global_id(0);
    for (int m = start[c] + 1, end = start[c + 1]; m < end; m++) {
        int v = order[m], p = m;
        for (; p > start[c] && order[p - 1] > v; p--)
            order[p] = order[p - 1];
        order[p] = v;
    }
}

/* the samples' grid places, weights and inverse depths in the list's order; slot: each
 * sample's place in the list (where the decimation writes it) */
__kernel void gather_permute(__global float *at_y, __global float *at_x, __global float *wt_at,
                             __global float *inv_at, __global int *slot,
                             __global const int *order, __global const float *gy,
                             __global const float *gx, __global const float *wt,
                             __global const float *inv_depth)
{
    int m = get_global_id(0), n = order[m];
    at_y[m] = gy[n];
    at_x[m] = gx[n];
    wt_at[m] = wt[n];
    inv_at[m] = inv_depth[n];
    slot[n] = m;
}

/* the weights of depth layer ``layer`` of ``layers``, spaced evenly in 1/depth from lo by
 * step (the last takes what lies beyond), 0 for the samples of the others */
__kernel void layer_weights(__global float *out, __global const float *wt,
                            __global const float *inv_at, float lo, float step, int layers,
                            int layer)
{
    int m = get_global_id(0);
    int which = clamp((int)floor((inv_at[m] - lo) / step), 0, layers - 1);
    out[m] = which == layer ? wt[m] : 0.0f;
}
