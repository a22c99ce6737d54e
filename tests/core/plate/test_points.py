"""The point-sum recorder (holo_core.plate.points): a diffuse mesh's points radiate as
independent emitters; points nearer than the plate's samples allow, or none, are refused by
name."""

import numpy as np
import pytest
from huge import never
from point_sums import square

from holo_core.plate.point_sum import Grid, cone_weight
from holo_core.plate.points import record_points
from holo_core.plate.record import record_hologram
from holo_core.plate.sampling import choose
from holo_core.propagation import grid
from holo_core.scene.mesh import sample_points
from holo_core.scene.plate import Plate
from holo_core.validate import InputError


def test_mesh_points_radiate_as_independent_emitters():
    """A diffuse mesh's points have independent random phases: the object wave's mean power
    is Σ I·w²/r² over the points (w their cone weight), within the speckle's scatter. (Phases
    drawn from the sampling's own random numbers once made each triangle coherent: 2.8x.)"""
    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
    holo = record_hologram(
        square(0.08, -0.3), plate=plate, resolution=128, depth=False, method="auto"
    )
    spacing = choose((0.1, 0.1), square(0.08, -0.3).vertices, resolution=128).spacing
    pos = sample_points(square(0.08, -0.3), spacing)[0]  # as record_hologram samples it
    g = Grid(holo.shape, holo.pitch, holo.wavelengths[0])._replace(
        fill=holo.band * 2 * holo.pitch / holo.wavelengths[0]
    )
    y, x = grid.coords(holo.shape[0], holo.pitch), grid.coords(holo.shape[1], holo.pitch)
    expected = np.zeros(holo.shape)
    for px, py, pz in pos:
        rho2 = (x[None] - px) ** 2 + (y[:, None] - py) ** 2
        expected += cone_weight(rho2, (g.cone * pz) ** 2) ** 2 / (rho2 + pz * pz)
    ratio = np.mean(np.abs(holo.object_wave[0]) ** 2) / expected.mean()
    assert 0.8 <= ratio <= 1.25, f"mean power over its expectation: {ratio:.3f}"


def test_points_nearer_than_the_plate_samples_are_refused_with_the_safe_distance():
    with pytest.raises(InputError, match=r"points need \|z\| >= 0.000\d+ m"):
        record_points([[0, 0, -4e-6]], [[1.0]], shape=(64, 64), pitch=8e-6, wavelengths=(633e-9,))


def test_no_points_are_refused():
    with pytest.raises(InputError, match="nothing to record"):
        record_points(
            np.zeros((0, 3)), np.zeros((0, 1)), shape=(8, 8), pitch=8e-6, wavelengths=(633e-9,)
        )


def test_a_hundred_million_point_sum_is_refused_before_its_amplitudes(monkeypatch):
    """10^8 points of three colours: (200 + 3·96) bytes each, 45.4 GiB, counted before their
    amplitudes and random phases are drawn."""
    import holo_core.plate.points as points

    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "8G")
    monkeypatch.setattr(points, "point_wave", never)
    n = 10**8
    with pytest.raises(
        InputError,
        match=r"100000000 point emitters of 3 wavelengths needs "
        r"45.4 GiB of memory",
    ):
        record_points(
            np.broadcast_to(np.array([0.0, 0.0, -0.01]), (n, 3)),
            np.broadcast_to(np.ones(3), (n, 3)),
            shape=(64, 64),
            pitch=8e-6,
            wavelengths=(633e-9, 532e-9, 473e-9),
        )
