"""A view's composition (holo_core.plate.composition) against wave optics: the depth from the
two-wavelength phase equals the point's planar depth, interfering points get a depth between
them, and averaged renders of independent random phases lower the speckle contrast as 1/√N
(Sect. VII-E)."""

import dataclasses
import math

import numpy as np
from accuracy import (
    DEPTH_SINGLE_POINT,
    SPECKLE_SQRT_N,
)
from point_views import EYE, LAM, camera, point_hologram

from holo_core.optics import speckle
from holo_core.optics.depth import partner_wavelength
from holo_core.plate.view import render_view
from holo_core.scene.camera import look_at


def depth_pair(half_range):
    lam2 = partner_wavelength(LAM, half_range)
    return (LAM, lam2), ("Y", "Z")


def test_two_wavelength_depth_of_a_point():
    """Eq. 26-30: the depth from the phase difference equals the true planar depth."""
    p = np.array([[0.05e-3, -0.03e-3, -3e-3]])
    lams, names = depth_pair(1e-3)
    cam = camera(2e-3, 48, matrix_world=look_at(EYE + [0.3e-3, 0, 0], (0, 0, -3e-3), up=(0, 1, 0)))
    for focus in (None, 6.5e-3):
        kw = {} if focus is None else dict(fstop=50e-3 / 0.1e-3, focus_distance=focus)
        cam_k = dataclasses.replace(cam, **kw)
        r = render_view(point_hologram(p, lams, names), cam_k)
        i, j = np.unravel_index(np.argmax(r.rgb[..., 0]), r.alpha.shape)
        true = cam_k.project(p)[1][0]
        assert abs(r.depth[i, j] / true - 1) <= DEPTH_SINGLE_POINT, (focus, r.depth[i, j], true)


def test_interfering_points_get_a_depth_between_them():
    """Two points on one pixel's ray interfere; keeping the brightest of several random-phase
    iterations puts the depth between them (Fig. 11)."""
    p = np.array([[0.05e-3, -0.03e-3, -3e-3], [0.05e-3, -0.03e-3, -3.4e-3]])
    lams, names = depth_pair(1e-3)
    cam = camera(2e-3, 32, matrix_world=look_at(EYE, p[0], up=(0, 1, 0)))
    r = render_view(point_hologram(p, lams, names, seeds=range(6)), cam)
    i, j = np.unravel_index(np.argmax(r.rgb[..., 0]), r.alpha.shape)
    near, far = sorted(cam.project(p)[1])
    assert near - 1e-6 <= r.depth[i, j] <= far + 1e-6, (r.depth[i, j], near, far)


def test_temporal_composition_lowers_speckle_as_one_over_sqrt_n(rng):
    """N renders of a diffuse patch (dense points, independent random phases per render),
    averaged: the speckle contrast falls as 1/√N (Sect. VII-E). The lens (0.3 mm) resolves
    spots holding some 5 points each, so that the points' placement, the same in every
    render, adds little contrast of its own (measured 1/N^0.41 against 1/√N: 17 %)."""
    n_pts, half = 3000, 0.15e-3
    p = np.column_stack([rng.uniform(-half, half, (n_pts, 2)), np.full(n_pts, -3e-3)])
    holos = point_hologram(p, n=1024, seeds=range(8))
    f = float(np.linalg.norm(EYE - [0, 0, -3e-3]))
    cam = camera(5e-4, 100, fstop=50e-3 / 0.3e-3, focus_distance=f)
    corners = cam.project([[-half, -half, -3e-3], [half, half, -3e-3]])[0]
    (c0, r1), (c1, r0) = corners + [[4, -4], [-4, 4]]
    inner = np.zeros((100, 100), bool)
    inner[int(r0) : int(r1), int(c0) : int(c1)] = True
    one = np.mean([speckle.contrast(render_view(h, cam).rgb[..., 0], inner) for h in holos[:3]])
    eight = speckle.contrast(render_view(holos, cam).rgb[..., 0], inner)
    assert abs(one / eight / math.sqrt(8) - 1) <= SPECKLE_SQRT_N, (one, eight)
