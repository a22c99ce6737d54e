/* The plate's samples against the carrier converging on the viewing zone: for each sample x,
 *
 *     B(x) = exp(ik(|x - Z| - Z_z)) · Σ_j a_j · w_j(x) · exp(ik(r_j(x) - |z_j|)) / r_j(x),
 *
 * the emitters j at p_j = (x_j, y_j, z_j) (z_j < 0) whose light leaves through x towards the
 * zone, w_j(x) their window towards the zone (a box, with a soft rim) times their visibility
 * from the zone point the ray p_j -> x reaches (bilinear between the zone's grid points). The
 * carrier exp(ik|z_j|)·exp(ikZ_z) comes folded into a_j from the host (float64).
 *
 * A work item owns a tile of VEC rows (the vector lanes) by SEG columns and writes it once. For
 * each emitter the phase k(r - |z|) is exact at the tile's centre (in REAL: double where the
 * device has it), each row's difference to it in float; along a row it follows its second-order
 * expansion about the segment centre by a recurrence (two complex multiplies per sample:
 * E <- E·D, D <- D·C, as in point_sum.cl). The window is a factor along x times one along y
 * (each of its box's axes with its rim): the one along y is a row's own, the segment's whole;
 * the one along x is 1 where it is at both of the segment's ends (the rim is millimetres wide,
 * a segment a fraction of one), else evaluated at each sample. The visibility varies over
 * centimetres: evaluated at the segment's two ends and taken linearly in between.
 *
 * Emitters are listed per block of BLOCK×BLOCK samples of the region computed (list[start[b] ..
 * start[b+1]), b counted from the region's first block): a work item reads its block's list
 * and skips the emitters whose footprint misses its tile.
 * Rows lie row_pitch apart, columns pitch apart (a zone wider than tall asks fewer rows).
 * An emitter's channels that share one phase (its colours: a_c = s_c·a, s_c real) come as a
 * (amp) and the shares s_c (shade): a starts the recurrence, and each channel adds s_c times the
 * light, a real multiply where a complex one was (SHADED; the shot's sums: 20 % less time).
 * Options: -DVEC=1|4|8|16, -DSEG=<columns>, -DCHANNELS=<n>, -DCHANNELS2=<n>, -DSHADED=0|1,
 * -DPARTNER_LERP=0|1, -DGRID_X, -DGRID_Y=<the zone grid's points along x, y>.
 */
#include "lane_series.h"

#ifndef CHANNELS2
#define CHANNELS2 0
#endif
#ifndef SHADED
#define SHADED 0
#endif
#ifndef PARTNER_LERP
#define PARTNER_LERP 0
#endif
#define ALL (CHANNELS + CHANNELS2)

/* the recurrence's start at the segment's first column for the wave number K: E its value,
 * D its step, C the step's step (the geometry, t, step_m and curve_m, shared by both). Every
 * phase CIS takes is wrapped: the curve's k·p²·ρ²/r³ passes π a sample where the samples lie
 * farther apart than an emitter's footprint (an emitter near the plate, a narrow zone), and
 * CIS's series holds on [-π, π] only (beyond, its terms overflow: non-finite samples) */
#define SERIES(K, er, ei, dr, di, cr, ci) {                                                  \
        real pc_ = (K) * rho2 / (rc + az);                                                  \
        pc_ -= (real)(2 * M_PI) * rint(pc_ * (real)(0.5 / M_PI));                           \
        float kf_ = (float)(K);                                                             \
        floatv phase_ = (float)pc_ + kf_ * (v * (2 * (float)dyc + v)) / (r + (float)rc);     \
        floatv d1i_ = kf_ * dx * inv_r, d2i_ = kf_ * c2f * inv_r2 * inv_r;                   \
        CIS(wrap(phase_ + d1i_ * u0 + d2i_ * (u0 * u0 / 2)), t, er, ei);                    \
        CIS(wrap(d1i_ * p + d2i_ * ud), step_m, dr, di);                                     \
        CIS(wrap(d2i_ * (p * p)), curve_m, cr, ci);                                          \
    }

/* E <- E·D, D <- D·C: two complex multiplies a sample */
#define ADVANCE(er, ei, dr, di, cr, ci) {                                                    \
        floatv t_ = er * dr - ei * di;                                                       \
        ei = er * di + ei * dr;                                                              \
        er = t_;                                                                             \
        t_ = dr * cr - di * ci;                                                              \
        di = dr * ci + di * cr;                                                              \
        dr = t_;                                                                             \
    }

/* (er, ei) times the complex w */
#define SCALE(er, ei, w) {                                                                   \
        float2 w_ = (w);                                                                     \
        floatv t_ = er * w_.x - ei * w_.y;                                                   \
        ei = er * w_.y + ei * w_.x;                                                          \
        er = t_;                                                                             \
    }

/* sample m's light (vr, vi) at the first wavelength, (vr2, vi2) at the partner's, into each
 * channel's sum; fma written out: each channel's sum is the same wherever it lies (looks
 * summed together equal looks summed alone). SHADED: each channel's a real share of the
 * light (its amplitude's phase and scale started the recurrence), else a complex amplitude */
#if SHADED
#define ADD(m, c, vr, vi) {                                                                  \
        acc_r[m][c] = fma(a[c], vr, acc_r[m][c]);                                            \
        acc_i[m][c] = fma(a[c], vi, acc_i[m][c]);                                            \
    }
#else
#define ADD(m, c, vr, vi) {                                                                  \
        acc_r[m][c] = fma(a[c].x, vr, fma(-a[c].y, vi, acc_r[m][c]));                        \
        acc_i[m][c] = fma(a[c].x, vi, fma(a[c].y, vr, acc_i[m][c]));                         \
    }
#endif
#define ADD_RANGE(m, c0, c1, vr, vi)                                                         \
        for (int c = c0; c < c1; c++)                                                        \
            ADD(m, c, vr, vi)
#define ACCUMULATE(m, vr, vi, vr2, vi2) {                                                    \
        floatv vr_ = (vr), vi_ = (vi);                                                       \
        ADD_RANGE(m, 0, CHANNELS, vr_, vi_);                                                 \
        vr_ = (vr2), vi_ = (vi2);                                                            \
        ADD_RANGE(m, CHANNELS, ALL, vr_, vi_);                                               \
    }
/* sample m's light weighted by w, at both wavelengths; then the recurrences' next sample.
 * PARTNER_LERP: the partner's light is the colours' E times K = ρ·exp(i(k2 − k)(r − |z|)),
 * which turns by less than PARTNER_TURN over a segment: K is exact at its two ends and linear
 * between (off by at most PARTNER_TURN²/8 of its size), a complex multiply-add a sample in
 * place of the partner's own recurrence */
#if PARTNER_LERP
#define LIGHT(m, w) {                                                                        \
        floatv vr_ = (w) * er, vi_ = (w) * ei;                                               \
        ADD_RANGE(m, 0, CHANNELS, vr_, vi_);                                                 \
        acc_r[m][CHANNELS] = fma(kr, vr_, fma(-ki, vi_, acc_r[m][CHANNELS]));                \
        acc_i[m][CHANNELS] = fma(kr, vi_, fma(ki, vr_, acc_i[m][CHANNELS]));                 \
    }
#define STEP { kr += dkr; ki += dki; ADVANCE(er, ei, dr, di, cr, ci); }
#elif CHANNELS2
#define LIGHT(m, w) ACCUMULATE(m, (w) * er, (w) * ei, (w) * er2, (w) * ei2)
#define STEP { ADVANCE(er2, ei2, dr2, di2, cr2, ci2); ADVANCE(er, ei, dr, di, cr, ci); }
#else
#define LIGHT(m, w) ACCUMULATE(m, (w) * er, (w) * ei, 0, 0)
#define STEP ADVANCE(er, ei, dr, di, cr, ci)
#endif

/* 1 - smoothstep over the rim: 1 inside |u| <= half, 0 beyond half + rim */
static floatv rim_weight(floatv u, floatv inner, float rim)
{
    floatv t = clamp((fabs(u) - inner) / rim, 0.0f, 1.0f);
    return (1.0f - t) * (1.0f - t) * (1.0f + 2.0f * t);
}

/* the emitter's window towards the zone where its ray through (x, y) reaches the zone's
 * centre plane, xi = p + s·(x - p) (s = (Z_z - z_j) / -z_j), relative to the zone's centre:
 * its box widened by the parallax of the box's depth, with a soft rim */
#define WINDOW_X(x) rim_weight((floatv)(xjf + s * ((x) - xjf)), ex + ez * fabs((x) - xjf) * inv_depth, \
                               rim_x)
#define WINDOW_Y(y) rim_weight(yjf + s * ((y) - yjf), ey + ez * fabs((y) - yjf) * inv_depth, rim_y)

/* the emitter's visibility from the zone point its ray through (x, y) reaches: bilinear over
 * the zone's GRID_Y x GRID_X points (table row ``row``), clamped to the grid's edge */
static floatv visibility(float x, floatv y, float xj, float yj, float s,
                         __global const uchar *vis, int row, float g0x, float g0y, float gsx,
                         float gsy)
{
    float xi = xj + s * (x - xj);
    floatv eta = yj + s * (y - yj);
    float fx = clamp((xi - g0x) / gsx, 0.0f, GRID_X - 1.0001f);
    floatv fy = clamp((eta - g0y) / gsy, 0.0f, GRID_Y - 1.0001f);
    int ix = (int)fx;
    float ax = fx - ix;
    __global const uchar *v = vis + row * GRID_X * GRID_Y;
    float lanes[VEC > 1 ? VEC : 1], fyl[VEC > 1 ? VEC : 1];
    UNLANE(fy, fyl);
    for (int l = 0; l < VEC; l++) {
        int iy = (int)fyl[l];
        float ay = fyl[l] - iy;
        int o = iy * GRID_X + ix;
        float a = v[o] * (1 - ax) + v[o + 1] * ax;
        float b = v[o + GRID_X] * (1 - ax) + v[o + GRID_X + 1] * ax;
        lanes[l] = (a * (1 - ay) + b * ay) * (1.0f / 255.0f);
    }
#if VEC == 1
    return lanes[0];
#else
    return CAT(vload, VEC)(0, lanes);
#endif
}

__kernel void zone_sum(__global float2 *out, int first_plane, int row_first, int col_first,
                       int oh, int ow,
                       real pitch, real row_pitch, real x0, real y0, real k, real k2,
                       real zx, real zy, real zz,
                       float ex, float ey, float ez, float rim_x, float rim_y,
                       __global const real *px, __global const real *py,
                       __global const real *pz, __global const float2 *amp,
                       __global const float2 *amp2, __global const float *shade,
                       __global const int *foot,       /* c0, c1, r0, r1 per emitter */
                       __global const int *vis_row, __global const uchar *vis,
                       float g0x, float g0y, float gsx, float gsy,
                       __global const int *list, __global const int *start, int blocks_x,
                       int block, int block_row0, int block_col0)
{
    int ty = get_global_id(0), tx = get_global_id(1);
    int row0 = row_first + ty * VEC, col0 = col_first + tx * SEG;
    int row_end = row_first + oh, col_end = col_first + ow;
    if (row0 >= row_end || col0 >= col_end)
        return;
    real half_seg = (SEG - 1) * (real)0.5 * pitch, half_rows = (VEC - 1) * (real)0.5 * row_pitch;
    real xc = x0 + col0 * pitch + half_seg;
    real yt = y0 + row0 * row_pitch + half_rows;
    floatv lane_v = (LANE_ID(LANES) - 0.5f * (VEC - 1)) * (float)row_pitch;
    float u0 = -(float)half_seg, p = (float)pitch;

    floatv acc_r[SEG][ALL], acc_i[SEG][ALL];
    for (int m = 0; m < SEG; m++)
        for (int c = 0; c < ALL; c++)
            acc_r[m][c] = acc_i[m][c] = 0;

    int b = (row0 / block - block_row0) * blocks_x + col0 / block - block_col0;
    for (int n = start[b], n1 = start[b + 1]; n < n1; n++) {
        int j = list[n];
        int4 f = vload4(j, foot);
        if (f.s1 < col0 || f.s0 >= col0 + SEG || f.s3 < row0 || f.s2 >= row0 + VEC)
            continue;
        real xj = px[j], yj = py[j], zj = pz[j], az = fabs(zj);
        real dxc = xc - xj, dyc = yt - yj, rho2 = dxc * dxc + dyc * dyc;
        real rc = sqrt(rho2 + zj * zj);
        float dx = (float)dxc;
        floatv v = lane_v, dy = (float)dyc + v;
        floatv c2f = dy * dy + (float)(zj * zj), r = sqrt(dx * dx + c2f);
        floatv inv_r = 1.0f / r, inv_r2 = inv_r * inv_r;
        floatv d1r = -dx * inv_r2, d2r = -(c2f - dx * dx) * inv_r2 * inv_r2;
        float ud = u0 * p + p * p / 2;
        floatv er, ei, dr, di, cr, ci, t;
        t = inv_r * exp_small(d1r * u0 + d2r * (u0 * u0 / 2));
        floatv step_m = exp_small(d1r * p + d2r * ud), curve_m = exp_small(d2r * (p * p));
        SERIES(k, er, ei, dr, di, cr, ci);
#if PARTNER_LERP  /* K at the segment's first and last columns (the phase as SERIES has it) */
        floatv kr, ki, dkr, dki;
        {
            float dk = (float)(k2 - k), u1 = u0 + (SEG - 1) * p;
            floatv at = (float)((k2 - k) * rho2 / (rc + az))
                        + dk * (v * (2 * (float)dyc + v)) / (r + (float)rc);
            floatv d1 = dk * dx * inv_r, d2 = dk * c2f * inv_r2 * inv_r;
            floatv ar, ai, br, bi;
            CIS(wrap(at + d1 * u0 + d2 * (u0 * u0 / 2)), 1.0f, ar, ai);
            CIS(wrap(at + d1 * u1 + d2 * (u1 * u1 / 2)), 1.0f, br, bi);
            float2 rho = amp2[j];
            kr = rho.x * ar - rho.y * ai;
            ki = rho.x * ai + rho.y * ar;
            dkr = (rho.x * br - rho.y * bi - kr) * (1.0f / (SEG - 1));
            dki = (rho.x * bi + rho.y * br - ki) * (1.0f / (SEG - 1));
        }
#elif CHANNELS2
        floatv er2, ei2, dr2, di2, cr2, ci2;  /* the partner wavelength's, same geometry */
        SERIES(k2, er2, ei2, dr2, di2, cr2, ci2);
#endif
#if SHADED  /* the channels' shared phase and scale starts the recurrence: it follows E */
        SCALE(er, ei, amp[j]);
#if CHANNELS2 && !PARTNER_LERP
        SCALE(er2, ei2, amp2[j]);
#endif
#endif

        /* the window: 1 over most segments; in its rim, evaluated at every sample */
        float s = (float)((zz - zj) / az), inv_depth = (float)(1 / az);
        float xjf = (float)(xj - zx), yjf = (float)(yj - zy);
        float xa = (float)(xc - half_seg - zx), xb = (float)(xc + half_seg - zx);
        floatv yr = (float)(yt - zy) + v;
        int row = vis_row[j];
        floatv va = 1, vstep = 0;
        if (row >= 0) {    /* the visibility varies over centimetres: linear along the segment */
            va = visibility(xa, yr, xjf, yjf, s, vis, row, g0x, g0y, gsx, gsy);
            floatv vb = visibility(xb, yr, xjf, yjf, s, vis, row, g0x, g0y, gsx, gsy);
            vstep = (vb - va) * (1.0f / (SEG > 1 ? SEG - 1 : 1));
        }
        /* the window's factor along y is a row's own (the lanes' y), the whole segment's;
         * along x it is 1 where both ends are (short footprints: most segments are in the
         * rim along y alone, and cost no window at each sample) */
        floatv wy = WINDOW_Y(yr);
        int flat_x = all(WINDOW_X(xa) == 1.0f) && all(WINDOW_X(xb) == 1.0f);
        int flat = flat_x && all(wy == 1.0f);
#if SHADED
        float a[ALL];
        for (int c = 0; c < ALL; c++)
            a[c] = shade[j * ALL + c];
        if (flat && row < 0) {  /* seen whole and inside the window: a weight of 1 */
            for (int m = 0; m < SEG; m++) {
                LIGHT(m, 1.0f);
                STEP;
            }
            continue;
        }
#else
        float2 a[ALL];
        for (int c = 0; c < CHANNELS; c++)
            a[c] = amp[j * CHANNELS + c];
        for (int c = CHANNELS; c < ALL; c++)
            a[c] = amp2[j * (ALL - CHANNELS) + c - CHANNELS];
#endif
        floatv vt = va;
        if (flat_x) {
            for (int m = 0; m < SEG; m++) {
                LIGHT(m, vt * wy);
                vt += vstep;
                STEP;
            }
            continue;
        }
        for (int m = 0; m < SEG; m++) {
            LIGHT(m, vt * (WINDOW_X(xa + m * p) * wy));
            vt += vstep;
            STEP;
        }
    }

    /* the carrier: exp(ik(|x - Z| - Z_z)) per sample, exact in REAL, its distance found once
     * for both wave numbers and its factor once for a wavelength's channels */
    float lane_r[VEC > 1 ? VEC : 1], lane_i[VEC > 1 ? VEC : 1];
    float2 carrier[2][VEC > 1 ? VEC : 1];
    int lanes = min(VEC, row_end - row0);
    for (int m = 0; m < SEG; m++) {
        int col = col0 + m;
        if (col >= col_end)
            break;
        real x = x0 + col * pitch - zx;
        for (int l = 0; l < lanes; l++) {
            real y = y0 + (row0 + l) * row_pitch - zy, rho2 = x * x + y * y;
            real to_zone = rho2 / (sqrt(rho2 + zz * zz) + zz);  /* |x - Z| - Z_z */
            for (int w = 0; w < (CHANNELS2 ? 2 : 1); w++) {
                real ph = (w ? k2 : k) * to_zone;
                ph -= (real)(2 * M_PI) * rint(ph * (real)(0.5 / M_PI));
                carrier[w][l] = cexpi((float)ph);
            }
        }
        for (int c = 0; c < ALL; c++) {
            UNLANE(acc_r[m][c], lane_r);
            UNLANE(acc_i[m][c], lane_i);
            for (int l = 0; l < lanes; l++)
                out[((long)(first_plane + c) * oh + row0 + l - row_first) * ow + col - col_first] =
                    cmul((float2)(lane_r[l], lane_i[l]), carrier[c >= CHANNELS][l]);
        }
    }
}

/* the looks' samples from the classes' sums (ZoneEmitters.classes; a class's ALL planes,
 * CHANNELS at the first wavelength then CHANNELS2 at the partner's): look l's channel c is
 * sum_k mixing[l, k] * sums[k, c], at each of ``plane`` samples, the looks' planes of the
 * first wavelength first, then the partner's */
__kernel void mix_classes(__global float2 *out, __global const float2 *sums,
                          __global const float2 *mixing, int looks, int classes, long plane)
{
    long n = get_global_id(0);
    int c = get_global_id(1);
    for (int l = 0; l < looks; l++) {
        float2 acc = 0;
        for (int k = 0; k < classes; k++)
            acc += cmul(mixing[l * classes + k], sums[(long)(k * ALL + c) * plane + n]);
        int to = c < CHANNELS ? l * CHANNELS + c
                              : looks * CHANNELS + l * CHANNELS2 + c - CHANNELS;
        out[(long)to * plane + n] = acc;
    }
}
