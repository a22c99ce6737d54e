"""A plate's object wave reconstructed (holo_core.plate.reconstruction): a carrier plate's is
its physical field, a full-band plate's its samples; a point-sum hologram's reconstruction
propagated back focuses every point where it was."""

import math

import numpy as np
from point_sums import LAM, PITCH, cloud
from zone_reference import carrier_plate

from holo_core.plate.carrier import physical_field
from holo_core.plate.points import record_points
from holo_core.plate.reconstruction import reconstruct
from holo_core.plate.reference import Reference
from holo_core.propagation import angular_spectrum
from holo_core.scene.hologram import Hologram
from holo_core.scene.plate import ViewingZone

ZONE = ViewingZone(centre=(0.01, -0.005, 0.3), half_extents=(0.03, 0.02, 0.01))
LAMBDA = 5e-6


def test_reconstruct_gives_a_complex_plates_object_wave(emitters):
    """A carrier plate's: the physical field on physical_field's default grid; a plate
    without a carrier: its samples."""
    h = carrier_plate(emitters, ZONE, LAMBDA)
    assert np.array_equal(reconstruct(h), physical_field(h).samples)
    full = Hologram(
        object_wave=h.object_wave, encoding="complex", wavelengths=h.wavelengths, pitch=h.pitch
    )
    assert np.array_equal(reconstruct(full), h.object_wave[0])
    f = physical_field(full, region=(-1e-3, -2e-3, 1e-3, 2e-3))
    rows = np.abs((np.arange(full.shape[0]) - (full.shape[0] - 1) / 2) * h.pitch) <= 2e-3
    cols = np.abs((np.arange(full.shape[1]) - (full.shape[1] - 1) / 2) * h.pitch) <= 1e-3
    assert np.array_equal(f.samples, h.object_wave[0][np.ix_(rows, cols)])


def test_reconstruction_focuses_every_point(rng):
    shape, z = (256, 256), -0.15
    pts = cloud(rng, z)
    holo = record_points(
        pts,
        np.ones((6, 1)),
        shape=shape,
        pitch=PITCH,
        wavelengths=(LAM,),
        reference=Reference(angle=0.03),
        seed=3,
    )
    image = (
        np.abs(angular_spectrum(reconstruct(holo), wavelength=LAM, pitch=PITCH, distance=z)) ** 2
    )
    for x, y, _ in pts:
        col, row = x / PITCH + (shape[1] - 1) / 2, y / PITCH + (shape[0] - 1) / 2
        r0, c0 = int(round(row)) - 6, int(round(col)) - 6
        win = image[r0 : r0 + 13, c0 : c0 + 13]
        pr, pc = np.unravel_index(win.argmax(), win.shape)
        off = math.hypot(r0 + pr - row, c0 + pc - col)
        assert off <= 1.0, f"point at ({x:.2e}, {y:.2e}) focuses {off:.2f} px away"
