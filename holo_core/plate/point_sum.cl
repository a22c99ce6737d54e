/* Object wave of point emitters on the plane z = 0 (Eq. 3), by a per-segment recurrence.
 *
 * A work item owns a tile of VEC rows (the vector lanes) by SEG columns. For each point the
 * complex log-field psi(x) = ln A(x) + i k (r(x) - |z|) of a row is expanded to second order
 * about the segment centre, exactly (the tile's centre phase in REAL, double where the device
 * has it; each row's difference to it in float); along the row
 * exp(psi) then costs two complex multiplies per pixel: E <- E*D, D <- D*C. The even and the
 * odd pixels run as two independent recurrences of two-pixel steps (E <- E*F, F <- F*C^4,
 * F = D*D' of a pixel and the next), so that the FMA units are not left waiting on one
 * chain's latency. PoCL does not vectorise scalar loops with builtins, hence the explicit
 * vector types. The carrier exp(ik|z|) and the amplitude come folded from the host
 * (float64).
 *
 * Each point reaches only the disc rho <= cone*|z| its pitch samples alias-free, with a smooth
 * rim (see point_sum.py, cone_weight). Points are read in [first, last), or, when
 * `binned`, sorted by the tile holding their centre, from the bins within (reach_x, reach_y)
 * tiles of this one (bin b's points start at bin_start[b]).
 * CHANNELS waves with the same wavelength and points (colours) share the geometry: each adds
 * its amplitude times exp(psi) to its own plane of `out` (stride h*w).
 * Options: -DVEC=1|4|8|16, -DSEG=<columns>, -DCHANNELS=<n>, -DOBLIQUITY (A = |z|/r^2
 * instead of 1/r). */
#include "lane_series.h"

#ifdef OBLIQUITY
#define NAMP 2
#else
#define NAMP 1
#endif

/* one pixel along the row: E <- E*D, D <- D*C */
#define STEP(er, ei, dr, di, cr, ci, t)   \
    do {                                  \
        t = er * dr - ei * di;            \
        ei = er * di + ei * dr;           \
        er = t;                           \
        t = dr * cr - di * ci;            \
        di = dr * ci + di * cr;           \
        dr = t;                           \
    } while (0)

/* the pixels of a segment, two at a time: the even chain (E0, F0) and the odd (E1, F1) */
#define PAIR_LOOP                                    \
    for (int m = 0; m < SEG; m += 2) {               \
        ADD(m, e0r, e0i);                            \
        ADD(m + 1, e1r, e1i);                        \
        STEP(e0r, e0i, f0r, f0i, c4r, c4i, t);       \
        STEP(e1r, e1i, f1r, f1i, c4r, c4i, t);       \
    }

/* the pixels of a segment in the cone's rim, weighted 1 - smoothstep(u) = (1-u)²(1+2u), where
 * the arguments give u from the pixel's column offset dx to the point */
#define KEEP(u) ((1.0f - (u)) * (1.0f - (u)) * (1.0f + 2.0f * (u)))
#define RIM_LOOP(...)                                                  \
    for (int m = 0; m < SEG; m += 2) {                                 \
        float dx = (float)m - xrel;                                    \
        floatv u0 = __VA_ARGS__;                                       \
        dx += 1.0f;                                                    \
        floatv u1 = __VA_ARGS__;                                       \
        floatv k0 = KEEP(u0), k1 = KEEP(u1);                           \
        ADD(m, k0 * e0r, k0 * e0i);                                    \
        ADD(m + 1, k1 * e1r, k1 * e1i);                                \
        STEP(e0r, e0i, f0r, f0i, c4r, c4i, t);                         \
        STEP(e1r, e1i, f1r, f1i, c4r, c4i, t);                         \
    }

/* acc[m][c] += v * amplitude c (with one channel the amplitude is folded into v already) */
#if CHANNELS == 1
#define ADD(m, vr, vi)           \
    do {                         \
        acc_r[m][0] += vr;       \
        acc_i[m][0] += vi;       \
    } while (0)
#else
#define ADD(m, vr, vi)                                     \
    do {                                                   \
        for (int c = 0; c < CHANNELS; c++) {               \
            acc_r[m][c] += a[c].x * (vr) - a[c].y * (vi);  \
            acc_i[m][c] += a[c].x * (vi) + a[c].y * (vr);  \
        }                                                  \
    } while (0)
#endif

__kernel void point_wave(__global float2 *out, int h, int w, real pitch, real x0, real y0,
                         real k, real cone2, real inner2,
                         __global const real *px, __global const real *py,
                         __global const real *pz, __global const float2 *amp,
                         int first, int last, int binned,
                         __global const int *bin_start, int reach_x, int reach_y)
{
    int ty = get_global_id(0), tx = get_global_id(1);
    int tiles_y = get_global_size(0), tiles_x = get_global_size(1);
    int row0 = ty * VEC, col0 = tx * SEG;
    real half_seg = (SEG - 1) * (real)0.5 * pitch, half_rows = (VEC - 1) * (real)0.5 * pitch;
    real xc = x0 + col0 * pitch + half_seg;              /* segment centre */
    real yt = y0 + row0 * pitch + half_rows;             /* tile centre row */
    floatv lane_v = (LANE_ID(LANES) - 0.5f * (VEC - 1)) * (float)pitch;  /* row - tile centre */
    real u0 = -half_seg, du = pitch;

    floatv acc_r[SEG][CHANNELS], acc_i[SEG][CHANNELS];
    for (int m = 0; m < SEG; m++)
        for (int c = 0; c < CHANNELS; c++)
            acc_r[m][c] = acc_i[m][c] = 0;

    /* the points to visit: one range, or one per bin row within reach */
    int by0 = max(ty - reach_y, 0), bx0 = max(tx - reach_x, 0);
    int bx1 = min(tx + reach_x, tiles_x - 1) + 1;
    int ranges = binned ? min(ty + reach_y, tiles_y - 1) - by0 + 1 : 1;
    for (int range = 0; range < ranges; range++)
    for (int j = binned ? bin_start[(by0 + range) * tiles_x + bx0] : first,
             j1 = binned ? bin_start[(by0 + range) * tiles_x + bx1] : last; j < j1; j++) {
        real xj = px[j], yj = py[j], zj = pz[j], az = fabs(zj);
        real rho_max2 = cone2 * zj * zj;
        real dxc = xc - xj;
        real ex = fmax(fabs(dxc) - half_seg, (real)0), ey = fmax(fabs(yt - yj) - half_rows, (real)0);
        if (ex * ex + ey * ey > rho_max2)
            continue;                                    /* tile outside the point's cone */
        /* k(r - |z|) at the tile's centre in REAL (float64 where the device has it), reduced;
         * each row adds k(r_l - r_c) = k·v(2·dy_c + v)/(r_l + r_c) in float, v its offset */
        real dyc = yt - yj, rho2 = dxc * dxc + dyc * dyc, rc = sqrt(rho2 + zj * zj);
        real pc = k * rho2 / (rc + az);
        pc -= (real)(2 * M_PI) * rint(pc * (real)(0.5 / M_PI));
        float dx = (float)dxc, kf = (float)k, u = (float)u0, p = (float)pitch;
        floatv v = lane_v, dy = (float)dyc + v;
        floatv c2f = dy * dy + (float)(zj * zj), r = sqrt(dx * dx + c2f);
        floatv phase = (float)pc + kf * (v * (2 * (float)dyc + v)) / (r + (float)rc);
        /* psi' and psi'' at the segment centre */
        floatv inv_r = 1.0f / r, inv_r2 = inv_r * inv_r;
        floatv d1r = -NAMP * dx * inv_r2, d1i = kf * dx * inv_r;
        floatv d2r = -NAMP * (c2f - dx * dx) * inv_r2 * inv_r2, d2i = kf * c2f * inv_r2 * inv_r;
        float ud = u * p + p * p / 2;
#ifdef OBLIQUITY
        floatv a0 = (float)az * inv_r2;
#else
        floatv a0 = inv_r;
#endif
        float2 a[CHANNELS];
        for (int c = 0; c < CHANNELS; c++)
            a[c] = amp[j * CHANNELS + c];
        floatv er, ei, dr, di, cr, ci, t;
        t = a0 * exp_small(d1r * u + d2r * (u * u / 2));
        CIS(wrap(phase + d1i * u + d2i * (u * u / 2)), t, er, ei);
#if CHANNELS == 1
        t = er * a[0].x - ei * a[0].y;
        ei = er * a[0].y + ei * a[0].x;
        er = t;
#endif
        CIS(wrap(d1i * p + d2i * ud), exp_small(d1r * p + d2r * ud), dr, di);
        CIS(wrap(d2i * (p * p)), exp_small(d2r * (p * p)), cr, ci);  /* CIS holds on ±π */
        /* the two chains: E1 = E0·D, F0 = D·(D·C), F1 = F0·C², both stepped by C⁴ */
        floatv e0r = er, e0i = ei, e1r, e1i, f0r, f0i, f1r, f1i, c2r, c2i, c4r, c4i;
        e1r = er * dr - ei * di;
        e1i = er * di + ei * dr;
        c2r = cr * cr - ci * ci;
        c2i = 2 * cr * ci;
        c4r = c2r * c2r - c2i * c2i;
        c4i = 2 * c2r * c2i;
        t = dr * cr - di * ci;                  /* D·C, the next pixel's D */
        floatv ti = dr * ci + di * cr;
        f0r = dr * t - di * ti;
        f0i = dr * ti + di * t;
        f1r = f0r * c2r - f0i * c2i;
        f1i = f0r * c2i + f0i * c2r;

        /* the cone's rim: weight 1 - smoothstep over rho² in [inner2, 1]·rho_max², which keeps
         * the rim's diffraction (a Poisson-spot term as strong as the wave) out of the sum */
        real far_x = fabs(dxc) + half_seg, far_y = fabs(yt - yj) + half_rows;
        if (far_x * far_x + far_y * far_y <= inner2 * rho_max2) {
            PAIR_LOOP
        } else {
            /* in pixel units, where float is ample for a weight */
            float pix2 = (float)(pitch * pitch), rim2 = (float)(rho_max2 / (pitch * pitch));
            float in2 = (float)inner2 * rim2, band = 1.0f / (rim2 - in2);
            floatv ub = (dy * dy / pix2 - in2) * band;   /* u = ub + dx²·band */
            float xrel = (float)((xj - xc + half_seg) / pitch);
            real near_x = ex, near_y = ey;
            if (near_x * near_x + near_y * near_y >= inner2 * rho_max2
                && far_x * far_x + far_y * far_y <= rho_max2) {
                RIM_LOOP(ub + dx * dx * band)   /* the tile lies within the rim: u in [0, 1] */
            } else {
                RIM_LOOP(clamp(ub + dx * dx * band, 0.0f, 1.0f))
            }
        }
    }

    float lane_r[VEC], lane_i[VEC];
    for (int c = 0; c < CHANNELS; c++)
    for (int m = 0; m < SEG; m++) {
        int col = col0 + m;
        UNLANE(acc_r[m][c], lane_r);
        UNLANE(acc_i[m][c], lane_i);
        for (int l = 0; l < VEC; l++) {
            int row = row0 + l;
            if (row < h && col < w)
                out[(c * h + row) * w + col] += (float2)(lane_r[l], lane_i[l]);
        }
    }
}
