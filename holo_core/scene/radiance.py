"""Radiance seen from a camera, carried onto the surfaces that show it.

A renderer's image of the emitters alone (Cycles' Combined pass, lit by the whole scene: direct
and indirect light, shadows, textures, normal maps, specular highlights towards that camera)
becomes each mesh's texture, and each vertex's UV is where that camera sees it: a projective
texture. A surface then emits, towards the camera, the radiance the renderer computed for it.
Hidden or back-facing parts take the radiance of what covers them; a camera hologram never
shows them, and a plate recorded for the camera keeps only the surfaces it sees
(:func:`holo_core.scene.mesh.visible_from`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..validate import InputError
from .camera import Camera
from .mesh import Mesh

MIN_ALPHA = 0.05  # coverage below which a pixel's radiance is taken from its neighbours
FILL_STEPS = 16  # pixels of growth of the covered region into the empty one
# An emitter of zero radiance would leave its depth without a phase (the depth is the phase
# of the colour against the depth partner, Eq. 26-29): none emits less than this share of the
# image's bright radiance (its 99th percentile), or than FLOOR_ABSOLUTE in an unlit image,
# far below what an 8-bit or a display shows (sRGB's first step is 3e-4).
FLOOR_RELATIVE = 1e-4
FLOOR_ABSOLUTE = 1e-6


def projected(meshes, camera: Camera, rgb, alpha) -> list[Mesh]:
    """``meshes`` textured with the radiance ``camera`` saw.

    Parameters
    ----------
    meshes : list of :class:`Mesh` in world metres
    camera : the camera of the image (its ``resolution`` is the image's (w, h) [px]; a crop
        of a larger view is :meth:`Camera.cropped`)
    rgb : (h, w, C) linear radiance premultiplied by ``alpha`` (a renderer's scene-linear
        units: emission of strength 1 shows as the colour itself), row 0 at the top
    alpha : (h, w) coverage in [0, 1]

    Each vertex's UV is its projection (the texel its pixel centre falls in, nearest texel);
    pixels of coverage below ``MIN_ALPHA`` take the mean of their covered neighbours, grown
    out ``FILL_STEPS`` pixels, so that points at the silhouette's rim find the rim's radiance.
    No texel is darker than the floor (``FLOOR_RELATIVE``, ``FLOOR_ABSOLUTE``) that keeps a
    surface in full shadow its depth.
    """
    rgb, alpha = np.asarray(rgb, np.float64), np.asarray(alpha, np.float64)
    w, h = camera.resolution
    if rgb.ndim != 3 or rgb.shape[:2] != (h, w) or alpha.shape != (h, w):
        raise InputError(
            f"radiance image must be ({h}, {w}, C) with alpha ({h}, {w}) for the "
            f"camera's {w}x{h} pixels; got {rgb.shape} and {alpha.shape}"
        )
    if not (np.isfinite(rgb).all() and np.isfinite(alpha).all()):
        raise InputError("radiance image must be finite")
    texture = filled(rgb, alpha)
    bright = np.percentile(texture, 99) if texture.size else 0.0
    texture = np.maximum(texture, max(FLOOR_RELATIVE * bright, FLOOR_ABSOLUTE))
    out = []
    for mesh in meshes:
        xy, depth = camera.project(mesh.vertices)
        xy = np.where(np.isfinite(xy) & (depth[:, None] > 0), xy, (w / 2, h / 2))
        u = np.clip(xy[:, 0], 0.5, w - 0.5) / w
        v = 1 - np.clip(xy[:, 1], 0.5, h - 0.5) / h
        out.append(replace(mesh, colours=None, uvs=np.stack([u, v], 1), texture=texture))
    return out


def filled(rgb, alpha) -> np.ndarray:
    """(h, w, C) radiance ≥ 0 unpremultiplied where covered (alpha ≥ ``MIN_ALPHA``) and grown
    from there into uncovered pixels; the mean covered radiance beyond (zero if none is)."""
    known = alpha >= MIN_ALPHA
    out = np.zeros_like(rgb)
    out[known] = np.maximum(rgb[known], 0) / alpha[known, None]  # a denoiser's undershoot: 0
    if not known.any():
        return out
    for _ in range(FILL_STEPS):
        if known.all():
            break
        total = np.zeros_like(out)
        count = np.zeros(known.shape)
        padded = np.pad(out * known[..., None], ((1, 1), (1, 1), (0, 0)))
        weight = np.pad(known.astype(float), 1)
        h, w = known.shape
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                total += padded[1 + dr : h + 1 + dr, 1 + dc : w + 1 + dc]
                count += weight[1 + dr : h + 1 + dr, 1 + dc : w + 1 + dc]
        grow = ~known & (count > 0)
        out[grow] = total[grow] / count[grow, None]
        known = known | grow
    out[~known] = out[known].mean(0)
    return out
