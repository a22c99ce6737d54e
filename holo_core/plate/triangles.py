"""Textured triangle emitters: each triangle's surface field on its own plane, carried to the
plate by spectrum rotation and offset propagation (Sect. IV-C, V-B). Diffuse surfaces get
uniformly random phases from a seeded generator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..propagation import propagate_to_plane
from ..scene.mesh import Mesh, surface_samples, texture_lookup, visible_from
from ..validate import InputError

# a primitive is recorded when the camera sees this share of its samples (a cube: its hidden faces
# 0-0.15 through their rims, a grazing seen face 0.47)
MIN_SEEN = 0.3


@dataclass(frozen=True, eq=False, kw_only=True)
class Primitive:
    """A textured triangle or quad: ``corners`` (3|4, 3) [m] in order around the edge, ``uvs``
    (3|4, 2) and a ``texture`` (h, w, C) of linear intensities (row 0 at v = 1)."""

    corners: np.ndarray
    uvs: np.ndarray
    texture: np.ndarray

    def frame(self):
        """(rotation, centre): columns ξ, η, ζ with ζ the normal towards +z, and the centroid."""
        p = np.asarray(self.corners, np.float64)
        xi = p[1] - p[0]
        zeta = np.cross(p[1] - p[0], p[-1] - p[0])
        if np.linalg.norm(zeta) == 0 or np.linalg.norm(xi) == 0:
            raise InputError("primitive corners are degenerate (zero area)")
        zeta = zeta / np.linalg.norm(zeta)
        if zeta[2] < 0:  # emit towards the hologram
            zeta = -zeta
        xi = xi / np.linalg.norm(xi)
        eta = np.cross(zeta, xi)
        return np.stack([xi, eta, zeta], axis=1), p.mean(axis=0)


def surface_field(prim: Primitive, *, pitch, channel=0, seed=0, diffuse=True):
    """The primitive's surface field on its own plane: (field (n, m) complex, the grid's centre
    in the local frame (ξ, η) [m]). √I from the texture, zero outside; a random phase per
    sample when ``diffuse`` (a rough surface), else phase 0 (a mirror-like emitter)."""
    m, centre = prim.frame()
    local = (np.asarray(prim.corners, np.float64) - centre) @ m  # (k, 3), third column ~0
    lo, hi = local[:, :2].min(0), local[:, :2].max(0)
    n = np.maximum(np.ceil((hi - lo) / pitch).astype(int) + 1, 1)
    mid = (lo + hi) / 2
    xi = (np.arange(n[0]) - (n[0] - 1) / 2) * pitch + mid[0]
    eta = (np.arange(n[1]) - (n[1] - 1) / 2) * pitch + mid[1]
    px, py = np.meshgrid(xi, eta)
    pts = np.stack([px.ravel(), py.ravel()], axis=1)
    inside = np.zeros(len(pts), bool)
    uv = np.zeros((len(pts), 2))
    tris = [(0, 1, 2)] if len(local) == 3 else [(0, 1, 2), (0, 2, 3)]
    for tri in tris:
        bary = _barycentric(pts, local[list(tri), :2])
        hit = (bary >= 0).all(axis=1)
        inside |= hit
        uv[hit] = bary[hit] @ np.asarray(prim.uvs, np.float64)[list(tri)]
    intensity = np.zeros(len(pts))
    intensity[inside] = texture_lookup(prim.texture, uv[inside])[:, channel]
    phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, len(pts)) if diffuse else 0.0
    field = (np.sqrt(intensity) * np.exp(1j * phase)).reshape(n[1], n[0])
    return field, mid


def _barycentric(p, tri):
    a, b, c = tri
    v0, v1, v2 = b - a, c - a, p - a
    d = v0[0] * v1[1] - v1[0] * v0[1]
    l1 = (v2[:, 0] * v1[1] - v1[0] * v2[:, 1]) / d
    l2 = (v0[0] * v2[:, 1] - v2[:, 0] * v0[1]) / d
    return np.stack([1 - l1 - l2, l1, l2], axis=1)


def surface_pitch(prim: Primitive, *, wavelength, pitch) -> float:
    """The sample spacing [m] on the primitive's plane that holds every direction the hologram
    (``pitch`` [m] at ``wavelength`` [m]) records: its Nyquist cone, tilted with the plane."""
    m, _ = prim.frame()
    tilt = math.acos(min(1.0, abs(m[2, 2])))
    accept = math.asin(min(1.0, wavelength / (2 * pitch)))
    return min(pitch, wavelength / (2 * math.sin(min(math.pi / 2, tilt + accept))))


def primitive_wave(
    prim: Primitive,
    *,
    wavelength,
    pitch,
    shape,
    channel=0,
    seed=0,
    padding=2,
    diffuse=True,
    sampled_for=None,
):
    """The primitive's wave on the hologram (z = 0, ``shape``, ``pitch`` [m]) at ``wavelength``
    [m]: its surface field, sampled at :func:`surface_pitch`, carried by spectrum rotation plus
    offset propagation (Sect. IV-D). ``sampled_for``: the shortest wavelength [m] of a set
    recorded together, so that all share one surface grid and so one diffuse phase pattern
    (the depth pair needs it)."""
    m, centre = prim.frame()
    q = surface_pitch(prim, wavelength=min(wavelength, sampled_for or wavelength), pitch=pitch)
    field, mid = surface_field(prim, pitch=q, channel=channel, seed=seed, diffuse=diffuse)
    grid_centre = centre + m[:, :2] @ mid  # the surface grid's centre in the hologram frame
    # the hologram plane seen from the primitive: axes = rows of m, centre at -grid_centre
    return propagate_to_plane(
        field.astype(np.complex64),
        wavelength=wavelength,
        pitch=q,
        rotation=m.T,
        position=m.T @ (-grid_centre),
        padding=padding,
        out_shape=shape,
        out_pitch=pitch,
    )


def mesh_primitives(mesh: Mesh, *, visible_to=None, spacing=None) -> list[Primitive]:
    """The mesh's triangles as primitives, textured by the mesh's texture or, without one,
    by the mean of their corners' colours; with a camera ``visible_to``, only those it sees
    (tested on points ``spacing`` [m] apart, see :func:`visible_from`)."""
    keep = np.arange(len(mesh.triangles))
    if visible_to is not None:  # seen: most of its samples (a hidden face's rim passes)
        tri, _, pos = surface_samples(mesh, spacing, 0, 2_000_000)
        seen = visible_from(visible_to, pos, spacing, mesh.normals()[tri])
        share = np.bincount(tri[seen], minlength=len(keep)) / np.maximum(
            np.bincount(tri, minlength=len(keep)), 1
        )
        keep = np.flatnonzero(share >= MIN_SEEN)
    prims = []
    for t in keep:
        idx = mesh.triangles[t]
        if mesh.texture is not None and mesh.uvs is not None:
            uvs, tex = mesh.uvs[idx], mesh.texture
        else:
            colour = (
                np.asarray(mesh.colours, np.float64)[idx].mean(0)
                if mesh.colours is not None
                else np.ones(3)
            )
            uvs, tex = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), colour[None, None, :]
        if np.linalg.norm(np.cross(*(mesh.vertices[idx[1:]] - mesh.vertices[idx[0]]))) > 0:
            prims.append(Primitive(corners=mesh.vertices[idx], uvs=uvs, texture=tex))
    return prims


def depth_texture(texture) -> np.ndarray:
    """The depth partner's texture: unit intensity, one channel (the recording scales it by
    the surface's cosine towards the camera). Its image is the surface's coverage of each
    pixel, whatever the colour, which gives the opacity mask; the depth pair's cross term
    u1·conj(u2) still weighs each emitter by its colour amplitude."""
    t = np.asarray(texture, np.float64)
    return np.ones(t.shape[:2] + (1,))
