/* Which emitters a point of the viewing zone sees (plate/emitters.py).
 *
 * depth_raster: one work item per triangle fills the depth buffer of the rays of a pupil's
 *     bins (kx, ky), b apart in direction cosine (FFT order, h x w): every bin of the
 *     triangle's box whose ray crosses it keeps the nearest planar depth (atomic min on the
 *     depth's bits: positive floats order as their integers). Vertices come as view tangents
 *     (tx, ty) and planar depth d, relative to the pupil.
 * seen_from: one work item per emitter: its direction and planar depth from the pupil, and the
 *     depth test against the buffer, bilinear between the four bins around its direction,
 *     with a slack for its surface's slope (bias_bins bins of it, plus bias_depth of the depth);
 *     an emitter of a closed surface (closed[e]) facing away from the pupil is not seen.
 *     The emitter comes as its offset from the zone's centre and its surface's normal; the
 *     pupil as its offset (ex, ey) from the centre in the zone's plane and the camera axes
 *     (rotation's columns), so the host hands the emitters over once for every pupil.
 */

/* Watertight, as optics/raster.py's crossings: a ray through an edge two triangles share
 * fills the buffer from exactly one of them, never from neither (a crack in the occluder that
 * the surfaces behind it show through, along every shared edge that runs through bins' rays).
 * Each edge's function is evaluated from the endpoint that comes first in (x, y) order, so
 * both triangles get the same number with opposite signs, and without contraction into fused
 * multiply-adds, which OpenCL C allows by default and which round a*b - c*d differently from
 * c*d - a*b; a ray exactly on the edge belongs to the triangle whose top or left edge it is. */
#pragma OPENCL FP_CONTRACT OFF

/* The edge function of p-q at r (twice the signed area of p, q, r), the same for q-p negated. */
static float edge_function(float px, float py, float qx, float qy, float rx, float ry)
{
    if (px > qx || (px == qx && py > qy))
        return -((px - qx) * (ry - qy) - (py - qy) * (rx - qx));
    return (qx - px) * (ry - py) - (qy - py) * (rx - px);
}

/* Whether a ray at edge function w (its sign made positive inside) of an edge running
 * (dx, dy) counter-clockwise is on the triangle's side: inside, or on a top or left edge. */
static bool covers(float w, float dx, float dy)
{
    return w > 0 || (w == 0 && (dy < 0 || (dy == 0 && dx < 0)));
}

__kernel void depth_raster(__global int *zbuf, int h, int w, float b,
                           __global const float *tx, __global const float *ty,
                           __global const float *d, __global const int *tri, int triangles)
{
    int t = get_global_id(0);
    if (t >= triangles)
        return;
    int i0 = tri[3 * t], i1 = tri[3 * t + 1], i2 = tri[3 * t + 2];
    float d0 = d[i0], d1 = d[i1], d2 = d[i2];
    if (!(d0 > 1e-9f && d1 > 1e-9f && d2 > 1e-9f))
        return;                              /* reaching behind the pupil: not seen */
    float ax = tx[i0], ay = ty[i0], bx = tx[i1], by = ty[i1], cx = tx[i2], cy = ty[i2];
    float area = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
    if (area == 0)
        return;
    /* the bins' box: direction cosines of the corners, one bin beyond (edges bend little) */
    float kx0 = 1e30f, kx1 = -1e30f, ky0 = 1e30f, ky1 = -1e30f;
    float px[3] = {ax, bx, cx}, py[3] = {ay, by, cy};
    for (int v = 0; v < 3; v++) {
        float n = sqrt(1 + px[v] * px[v] + py[v] * py[v]);
        float kx = -px[v] / n / b, ky = -py[v] / n / b;
        kx0 = fmin(kx0, kx); kx1 = fmax(kx1, kx); ky0 = fmin(ky0, ky); ky1 = fmax(ky1, ky);
    }
    int c0 = max((int)floor(kx0) - 1, -(w / 2)), c1 = min((int)ceil(kx1) + 1, (w - 1) / 2);
    int r0 = max((int)floor(ky0) - 1, -(h / 2)), r1 = min((int)ceil(ky1) + 1, (h - 1) / 2);
    float s = area > 0 ? 1.0f : -1.0f;  /* counter-clockwise whichever way it is wound */
    for (int ky = r0; ky <= r1; ky++)
    for (int kx = c0; kx <= c1; kx++) {
        float alpha = kx * b, beta = ky * b;
        float gamma = sqrt(fmax(1 - alpha * alpha - beta * beta, 1e-12f));
        float rx = -alpha / gamma, ry = -beta / gamma;
        float w0 = s * edge_function(bx, by, cx, cy, rx, ry);  /* the edges facing a, b, c */
        float w1 = s * edge_function(cx, cy, ax, ay, rx, ry);
        float w2 = s * edge_function(ax, ay, bx, by, rx, ry);
        if (!(covers(w0, s * (cx - bx), s * (cy - by)) && covers(w1, s * (ax - cx), s * (ay - cy))
              && covers(w2, s * (bx - ax), s * (by - ay))))
            continue;
        float l1 = w1 / (w0 + w1 + w2), l2 = w2 / (w0 + w1 + w2);
        float inv = (1 - l1 - l2) / d0 + l1 / d1 + l2 / d2;
        int flat = (ky < 0 ? ky + h : ky) * w + (kx < 0 ? kx + w : kx);
        atomic_min(zbuf + flat, as_int(1 / inv));
    }
}

__kernel void seen_from(__global float *seen, int point, __global const float *zbuf, int h,
                        int w, float b, __global const float *px, __global const float *py,
                        __global const float *pz, __global const float *nx,
                        __global const float *ny, __global const float *nz, float ex, float ey,
                        __constant float *axes, float max_slope, float bias_bins,
                        float bias_depth, __global const uchar *closed, int emitters)
{
    int e = get_global_id(0);
    if (e >= emitters)
        return;
    float3 p = (float3)(px[e] - ex, py[e] - ey, pz[e]);  /* from the pupil, plate's axes */
    float x = p.x * axes[0] + p.y * axes[3] + p.z * axes[6];  /* ... along the camera's */
    float y = p.x * axes[1] + p.y * axes[4] + p.z * axes[7];   /* (the rotation's columns) */
    float z = p.x * axes[2] + p.y * axes[5] + p.z * axes[8];
    float dist = sqrt(x * x + y * y + z * z), depth = -z;
    float facing = (nx[e] * p.x + ny[e] * p.y + nz[e] * p.z) / dist;
    /* a closed surface's point whose outward normal turns away from the pupil is its far
     * side: never seen, though near a silhouette the depth test's slope slack (below) would
     * pass it (the far side's light then swelled the silhouettes by half a pixel) */
    if (closed[e] && facing > 0) {
        seen[(long)point * emitters + e] = 0;
        return;
    }
    float cosine = fabs(facing);
    float slope = fmin(sqrt(fmax(1 - cosine * cosine, 0.0f)) / fmax(cosine, 1e-9f), max_slope);
    float kx = -x / dist / b, ky = -y / dist / b;
    float bias = (bias_bins * b * slope + bias_depth) * depth;
    int x0 = (int)floor(kx), y0 = (int)floor(ky);
    float fx = kx - x0, fy = ky - y0, acc = 0;
    for (int dy = 0; dy < 2; dy++)
    for (int dx = 0; dx < 2; dx++) {
        int r = y0 + dy, c = x0 + dx;
        r = r < 0 ? r + h : r;
        c = c < 0 ? c + w : c;
        if (r < 0 || r >= h || c < 0 || c >= w)
            continue;
        float weight = (dy ? fy : 1 - fy) * (dx ? fx : 1 - fx);
        acc += weight * (depth <= zbuf[r * w + c] + bias);
    }
    seen[(long)point * emitters + e] = acc;
}
