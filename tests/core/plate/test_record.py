"""Holograms recorded from a scene's points or meshes (holo_core.plate.record): one of a
wavelength long against the plate's pitch gets a sampling cone it can store, written and read
back."""

import numpy as np

from holo_core.io.hologram import read_hologram, write_hologram
from holo_core.plate.record import record_hologram
from holo_core.scene.plate import Plate


def test_a_long_wavelength_hologram_is_written_and_read_back(tmp_path):
    """A wavelength long against the pitch (λ = 1 mm on a 39 µm pitch, where 0.95·λ2/8p
    = 1.69) gets a cone of sin θ < 1, which the file holds: written and read back alike."""
    plate = Plate(matrix_world=np.eye(4), width=0.0025, height=0.0025)
    h = record_hologram(
        ([[0.0, 0.0, -0.05]], [[1.0, 1.0, 1.0]]), plate=plate, resolution=64, wavelength=1e-3
    )
    assert 0 < h.band < 1, f"band sin θ = {h.band}"
    back = read_hologram(write_hologram(tmp_path / "h.exr", h))
    assert back.band == h.band and back.wavelengths == h.wavelengths
