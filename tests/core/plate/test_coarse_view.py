"""A coarse view's camera and its upsampling (holo_core.plate.coarse_view) keep the rays: a
camera n times coarser has its pixel centres on the mean of the fine pixels' n×n blocks,
whatever its shifts, and a linear ramp is upsampled exactly, its edges held."""

import numpy as np
import plate_scene as ps
import pytest

from holo_core.plate.coarse_view import coarser, upsampled


@pytest.mark.parametrize("factor", [2, 4])
def test_a_coarser_cameras_pixels_are_the_fine_blocks_means(factor):
    cam = ps.camera("centre", scale=ps.SMALL)
    small = coarser(cam, factor)
    w, h = cam.resolution
    assert small.resolution == (-(-w // factor), -(-h // factor))
    for fine, coarse in zip(cam.pixel_tangents(), small.pixel_tangents()):
        rows, cols = (h // factor) * factor, (w // factor) * factor
        block = fine[:rows, :cols].reshape(rows // factor, factor, cols // factor, factor)
        mean = block.mean((1, 3))
        err = np.abs(coarse[: rows // factor, : cols // factor] - mean).max()
        assert err < 1e-12, err
    assert coarser(cam, 1) is cam


def test_a_linear_ramp_is_upsampled_exactly_and_its_edges_held():
    ramp = np.arange(4.0)[None, :] * np.ones((3, 1))  # linear in the coarse pixel's centre
    up = upsampled(ramp, 2, (6, 8))
    assert np.allclose(up[0, 1:7], (np.arange(1, 7) + 0.5) / 2 - 0.5), up[0]
    assert up[0, 0] == 0 and up[0, 7] == 3
    assert upsampled(ramp, 1, (3, 4)) is ramp
