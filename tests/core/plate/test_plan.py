"""Plates as scene assets: the viewing zone, and the sampling planned from it and the optics
(the band from every object point towards the whole zone, the wavelength from the pitch and
that band, the view's resolution λ/D of the camera's lens, not the pinhole rule)."""

import json
import math

import numpy as np
import pytest

from holo_core.__main__ import main
from holo_core.io.hologram import read_hologram, write_hologram
from holo_core.io.image import read_exr, write_exr
from holo_core.optics.pupil import pinhole_wavelength
from holo_core.plate.sampling import MARGIN, SHARP_SPOT, band_towards_zone, plan, plan_view
from holo_core.scene.hologram import Hologram
from holo_core.scene.plate import ViewingZone

BOX = np.array([[-0.02, -0.015, -0.33], [0.025, 0.02, -0.28]])
ZONE = ViewingZone(centre=(0.01, -0.005, 0.3), half_extents=(0.04, 0.03, 0.02), pupil=0.05 / 2.8)


def test_band_is_the_widest_line_from_the_objects_to_the_zone(rng):
    """The corners' answer is the widest of every pair of points of the two boxes: 11 points
    per axis in each box (the corners among them) reach it, and 200,000 random pairs inside
    stay below it."""
    axes = [np.linspace(lo, hi, 11) for lo, hi in zip(*BOX)]
    a = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    zone_lo, zone_hi = np.subtract(ZONE.centre, ZONE.half_extents), np.add(ZONE.centre,
                                                                        ZONE.half_extents)
    axes = [np.linspace(lo, hi, 11) for lo, hi in zip(zone_lo, zone_hi)]
    b = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    widest = 0.0
    for chunk in np.array_split(a, 20):
        v = b[None] - chunk[:, None]
        widest = max(widest, float(np.max(np.hypot(v[..., 0], v[..., 1])
                                          / np.linalg.norm(v, axis=-1))))
    v = rng.uniform(zone_lo, zone_hi, (200_000, 3)) - rng.uniform(BOX[0], BOX[1], (200_000, 3))
    inside = float(np.max(np.hypot(v[:, 0], v[:, 1]) / np.linalg.norm(v, axis=1)))
    exact = band_towards_zone(BOX, ZONE)
    print(f"band: corners {exact:.6f}, grid {widest:.6f}, random inside {inside:.6f}")
    assert widest == pytest.approx(exact, rel=1e-12) and inside < exact, (exact, widest, inside)


def test_wavelength_comes_from_the_pitch_and_the_band_not_the_pinhole_rule():
    """λ = 2·pitch·sin θ/margin for a complex plate (λ2 of the depth pair at the limit), 8·
    for an intensity one (its carrier, twin and |O|² terms); a lens camera's view then
    resolves λ/D, half the samples doubling it, and the planner's sharp sample count gives
    half a pixel. The pinhole rule λ = 4Δ²r would give another wavelength altogether."""
    pixel = 36 / 50 / 640
    complex_ = plan((0.1, 0.1), BOX, zone=ZONE, resolution=4096)
    intensity = plan((0.1, 0.1), BOX, zone=ZONE, resolution=4096, encoding="intensity")
    band = band_towards_zone(BOX, ZONE)
    assert complex_.band == pytest.approx(band)
    assert complex_.depth_wavelength == pytest.approx(2 * complex_.pitch * band / MARGIN,
                                                      rel=1e-12)
    assert intensity.depth_wavelength / complex_.depth_wavelength == pytest.approx(4)
    assert math.sin(intensity.reference_angle) == pytest.approx(3 * band)
    eye = np.array([0.01, -0.005, 0.3])
    view = plan_view(complex_, position=eye, pixel_angle=pixel, pupil=ZONE.pupil)
    assert view.spot_px == pytest.approx(complex_.wavelength / (ZONE.pupil * pixel))
    half = plan_view(plan((0.1, 0.1), BOX, zone=ZONE, resolution=2048), position=eye,
                     pixel_angle=pixel, pupil=ZONE.pupil)
    assert half.spot_px == pytest.approx(2 * view.spot_px, rel=1e-3)
    sharp = plan((0.1, 0.1), BOX, zone=ZONE, resolution=half.sharp_samples)
    spot = plan_view(sharp, position=eye, pixel_angle=pixel, pupil=ZONE.pupil).spot_px
    assert spot <= SHARP_SPOT and spot > 0.99 * SHARP_SPOT, spot
    pinhole = pinhole_wavelength(pixel, 0.6)
    print(f"λ = {complex_.wavelength:.3g} m (pinhole rule {pinhole:.3g} m), spot "
          f"{view.spot_px:.2f} px, {half.sharp_samples} samples for {SHARP_SPOT} px")
    assert abs(complex_.wavelength / pinhole - 1) > 0.5


def test_planner_on_the_command_line(capsys):
    """`python -m holo_core plan` states the samples a sharp view needs, the memory, the time
    and, for a plate too small, the blur its views will have."""
    assert main(["plan", "--box", "0.06", "0.05", "0.09", "--distance", "0.27",
                 "--samples", "1024"]) == 0
    out = capsys.readouterr().out
    print(out)
    for word in ("1024 x 1024 samples", "λ =", "memory", "recording   about", "blurred to",
                 "sharp view  needs", "per view"):
        assert word in out, word
    blur = float(out.split("blurred to about ")[1].split()[0])
    need = int(out.split("sharp view  needs ")[1].split()[0])
    assert blur == pytest.approx(SHARP_SPOT * need / 1024, rel=0.02), (blur, need)
    assert main(["plan", "--box", "0.06", "0.05", "0.09", "--distance", "0.27"]) == 0
    assert "sharp\n" in capsys.readouterr().out


def test_complex_plate_file_keeps_its_zone(tmp_path, rng):
    """A complex plate (the object wave, no intensity) and its viewing zone go through the
    file bit-exactly; a version 2 file (intensity, no zone) still reads."""
    wave = (rng.standard_normal((4, 12, 20)) + 1j * rng.standard_normal((4, 12, 20))
            ).astype(np.complex64)
    h = Hologram(object_wave=wave, encoding="complex", wavelengths=(9e-6,) * 3 + (8.99e-6,),
                 pitch=2.4e-5, channels=("R", "G", "B", "Z"), zone=ZONE, band=0.17,
                 bounds=BOX, point_density=3e6)
    back = read_hologram(write_hologram(tmp_path / "plate.exr", h))
    assert back.encoding == "complex" and back.intensity is None
    assert back.object_wave.tobytes() == wave.tobytes()
    assert back.zone.centre == ZONE.centre and back.zone.half_extents == ZONE.half_extents
    assert back.zone.pupil == ZONE.pupil
    header, channels = read_exr(tmp_path / "plate.exr")
    assert not any(name.endswith(".H") for name in channels)
    old = json.loads(header["holo"])
    for key in ("encoding", "viewing_zone"):
        del old[key]
    old["format_version"] = 2
    old["object_wave"] = False
    write_exr(tmp_path / "v2.exr", {f"c{c}.H": np.abs(wave[c]) ** 2 for c in range(4)},
              holo=json.dumps(old))
    v2 = read_hologram(tmp_path / "v2.exr")
    assert v2.encoding == "intensity" and v2.zone is None and v2.shape == (12, 20)
