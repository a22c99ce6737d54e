/* Object wave of point emitters on the plane z = 0 (Eq. 3), by a per-segment recurrence.
 *
 * A work item owns a tile of VEC rows (the vector lanes) by SEG columns. For each point the
 * complex log-field psi(x) = ln A(x) + i k (r(x) - |z|) of a row is expanded to second order
 * about the segment centre, exactly (REAL is double where the device has it); along the row
 * exp(psi) then costs two complex multiplies per pixel: E <- E*D, D <- D*C. PoCL does not
 * vectorise scalar loops with builtins, hence the explicit vector types. The carrier
 * exp(ik|z|) and the amplitude come folded from the host (float64).
 *
 * Each point reaches only the disc rho <= cone*|z| its pitch samples alias-free, with a smooth
 * rim (see point_sources.py, cone_weight). Points are read in [first, last), or, when
 * `binned`, from this tile's list in `order`.
 * Options: -DVEC=1|4|8|16, -DSEG=<columns>, -DOBLIQUITY (A = |z|/r^2 instead of 1/r). */
#include "holo_complex.h"

#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)
#ifdef HOLO_FP64
typedef double real;
#define REALNAME double
#else
typedef float real;
#define REALNAME float
#endif

#if VEC == 1
typedef float floatv;
typedef real realv;
#define TO_FLOAT(x) ((float)(x))
#define TO_REAL(x) ((real)(x))
#define LANE_ID(c) 0.0f
#else
typedef CAT(float, VEC) floatv;
typedef CAT(REALNAME, VEC) realv;
#define TO_FLOAT(x) CAT(convert_float, VEC)(x)
#define TO_REAL(x) CAT(CAT(convert_, REALNAME), VEC)(x)
#define LANE_ID(c) CAT(vload, VEC)(0, c)
#endif

#ifdef OBLIQUITY
#define NAMP 2
#else
#define NAMP 1
#endif

__constant float LANES[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};

/* Builtin exp and sincos are library calls on PoCL, slower than the whole recurrence: the
 * arguments here are small, so short series do (errors below 1e-8). */
static floatv wrap(floatv x)            /* x reduced to [-pi, pi] */
{
    return x - 6.28318531f * rint(x * 0.159154943f);
}

static floatv exp_small(floatv x)       /* exp(x), |x| << 1 (a relative amplitude change) */
{
    return 1 + x * (1 + x * (0.5f + x * (1 / 6.0f + x * (1 / 24.0f + x * (1 / 120.0f
           + x * (1 / 720.0f))))));
}

/* (re, im) = m * exp(i x) for x in [-pi, pi] */
#define CIS(x, m, re, im)                  \
    do {                                   \
        floatv cos_, sin_;                 \
        HOLO_CIS(floatv, x, cos_, sin_);   \
        re = (m) * cos_;                   \
        im = (m) * sin_;                   \
    } while (0)

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

__kernel void point_wave(__global float2 *out, int h, int w, real pitch, real x0, real y0,
                         real k, real cone2, real inner2,
                         __global const real *px, __global const real *py,
                         __global const real *pz, __global const float2 *amp,
                         int first, int last, int binned,
                         __global const int *tile_start, __global const int *order)
{
    int ty = get_global_id(0), tx = get_global_id(1), tiles_x = get_global_size(1);
    int row0 = ty * VEC, col0 = tx * SEG;
    real half_seg = (SEG - 1) * (real)0.5 * pitch, half_rows = (VEC - 1) * (real)0.5 * pitch;
    real xc = x0 + col0 * pitch + half_seg;              /* segment centre */
    real yt = y0 + row0 * pitch + half_rows;             /* tile centre row */
    realv yrow = y0 + (row0 + TO_REAL(LANE_ID(LANES))) * pitch;
    real u0 = -half_seg, du = pitch;

    floatv acc_r[SEG], acc_i[SEG];
    for (int m = 0; m < SEG; m++)
        acc_r[m] = acc_i[m] = 0;

    int n0 = binned ? tile_start[ty * tiles_x + tx] : first;
    int n1 = binned ? tile_start[ty * tiles_x + tx + 1] : last;
    for (int q = n0; q < n1; q++) {
        int j = binned ? order[q] : q;
        real xj = px[j], yj = py[j], zj = pz[j], az = fabs(zj);
        real rho_max2 = cone2 * zj * zj;
        real dxc = xc - xj;
        real ex = fmax(fabs(dxc) - half_seg, (real)0), ey = fmax(fabs(yt - yj) - half_rows, (real)0);
        if (ex * ex + ey * ey > rho_max2)
            continue;                                    /* tile outside the point's cone */
        realv dy = yrow - yj;
        realv c2 = dy * dy + zj * zj, r = sqrt(dxc * dxc + c2);
        realv phase = k * (dxc * dxc + dy * dy) / (r + az);  /* k(r - |z|): the only float64 */
        phase -= (real)(2 * M_PI) * rint(phase * (real)(0.5 / M_PI));
        /* psi' and psi'' at the segment centre, in float */
        floatv inv_r = 1.0f / TO_FLOAT(r), inv_r2 = inv_r * inv_r, c2f = TO_FLOAT(c2);
        float dx = (float)dxc, kf = (float)k, u = (float)u0, p = (float)pitch;
        floatv d1r = -NAMP * dx * inv_r2, d1i = kf * dx * inv_r;
        floatv d2r = -NAMP * (c2f - dx * dx) * inv_r2 * inv_r2, d2i = kf * c2f * inv_r2 * inv_r;
        float ud = u * p + p * p / 2;
#ifdef OBLIQUITY
        floatv a0 = (float)az * inv_r2;
#else
        floatv a0 = inv_r;
#endif
        float2 a = amp[j];
        floatv er, ei, dr, di, cr, ci, t;
        t = a0 * exp_small(d1r * u + d2r * (u * u / 2));
        CIS(wrap(TO_FLOAT(phase) + d1i * u + d2i * (u * u / 2)), t, er, ei);
        t = er * a.x - ei * a.y;
        ei = er * a.y + ei * a.x;
        er = t;
        CIS(wrap(d1i * p + d2i * ud), exp_small(d1r * p + d2r * ud), dr, di);
        CIS(d2i * (p * p), exp_small(d2r * (p * p)), cr, ci);

        /* the cone's rim: weight 1 - smoothstep over rho² in [inner2, 1]·rho_max², which keeps
         * the rim's diffraction (a Poisson-spot term as strong as the wave) out of the sum */
        real far_x = fabs(dxc) + half_seg, far_y = fabs(yt - yj) + half_rows;
        if (far_x * far_x + far_y * far_y <= inner2 * rho_max2) {
            for (int m = 0; m < SEG; m++) {
                acc_r[m] += er;
                acc_i[m] += ei;
                STEP(er, ei, dr, di, cr, ci, t);
            }
        } else {
            /* in pixel units, where float is ample for a weight */
            float pix2 = (float)(pitch * pitch), rim2 = (float)(rho_max2 / (pitch * pitch));
            float in2 = (float)inner2 * rim2, band = 1.0f / (rim2 - in2);
            floatv dy2 = TO_FLOAT(dy * dy) / pix2;
            float xrel = (float)((xj - xc + half_seg) / pitch);
            for (int m = 0; m < SEG; m++) {
                float dx = (float)m - xrel;
                floatv u = clamp((dx * dx + dy2 - in2) * band, 0.0f, 1.0f);
                floatv keep = 1.0f - u * u * (3.0f - 2.0f * u);
                acc_r[m] += keep * er;
                acc_i[m] += keep * ei;
                STEP(er, ei, dr, di, cr, ci, t);
            }
        }
    }

    float lane_r[VEC], lane_i[VEC];
    for (int m = 0; m < SEG; m++) {
        int col = col0 + m;
#if VEC == 1
        lane_r[0] = acc_r[m];
        lane_i[0] = acc_i[m];
#else
        CAT(vstore, VEC)(acc_r[m], 0, lane_r);
        CAT(vstore, VEC)(acc_i[m], 0, lane_i);
#endif
        for (int l = 0; l < VEC; l++) {
            int row = row0 + l;
            if (row < h && col < w)
                out[row * w + col] += (float2)(lane_r[l], lane_i[l]);
        }
    }
}
