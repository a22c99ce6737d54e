"""A scan to a view in one step: a peer's off-axis optical hologram (tests/scans.py: float64
NumPy, no code of Holo's recorder) imported on the command line with its pitch, wavelength and
distance alone, its view measured against the ground truth."""

import contextlib
import io
import math
import re

import numpy as np
import pytest
import scans
from cli import run_cli

from holo_core.__main__ import main
from holo_core.acquired import (
    autofocus,
    decimate,
    default_camera,
    depth_of_focus,
    import_acquired,
)
from holo_core.io.hologram import read_hologram
from holo_core.io.image import read_exr
from holo_core.validate import UnitWarning

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    """``python -m holo_core import letter_scan_2048.png --pitch 3.45um --wavelength 633
    --distance 5cm -o out/``: its printed lines, the hologram and the view it wrote."""
    folder = tmp_path_factory.mktemp("scan")
    scan = scans.optical_scan(folder)
    out = folder / "out"
    out.mkdir()
    with contextlib.redirect_stdout(io.StringIO()) as stdout:
        status = main(
            [
                "import",
                str(scan),
                "--pitch",
                "3.45um",
                "--wavelength",
                "633",
                "--distance",
                "5cm",
                "-o",
                f"{out}/",
            ]
        )
    assert status == 0, stdout.getvalue()
    hologram = read_hologram(out / "letter_scan_2048_holo.exr")
    _, channels = read_exr(out / "letter_scan_2048_view.exr")
    view = {k.split(".", 1)[1]: v for k, v in channels.items()}
    return stdout.getvalue(), hologram, view, scan


def truth_in_view(hologram, camera):
    """The ground truth seen by ``camera``: for each pixel, the letter where its ray meets the
    objects' plane (tests/scans.py's letter at z = −distance)."""
    tx, ty = camera.pixel_tangents()
    rays = np.stack([tx, ty, -np.ones_like(tx)], -1) @ camera.rotation.T
    eye = camera.position
    t = (-scans.DISTANCE - eye[2]) / rays[..., 2]
    x, y = eye[0] + t * rays[..., 0], eye[1] + t * rays[..., 1]
    return scans.letter(x, y), (x, y)


def test_the_carrier_is_found_and_reported(imported):
    """The carrier the scan was made with, found by the rule: the order that focuses 5 cm
    behind (the spectrum's 'upper' one here, f_y < 0), its angle and azimuth printed."""
    stdout, hologram, _, _ = imported
    fx, fy = scans.CARRIER
    angle, azimuth = math.asin(math.hypot(fx, fy) * scans.WAVELENGTH), math.atan2(fy, fx)
    printed = re.search(r"reference ([-\d.e]+) rad .* at azimuth ([-\d.e]+) rad", stdout)
    assert printed, stdout
    assert float(printed[1]) == pytest.approx(angle, rel=1e-4), stdout
    assert float(printed[2]) == pytest.approx(azimuth, abs=1e-4), stdout
    assert hologram.encoding == "complex" and hologram.bounds[0][2] == -scans.DISTANCE


def test_the_view_shows_the_letter_where_it_is(imported):
    """The view of the camera that frames the plate, focused at 5 cm: IoU >= 0.95 against the
    ground truth, the dot found on the right (where the truth has it, right of the letter's
    centre; the mirrored letter matches far worse), the letter's scale within 1 % (the dot's
    distance to the letter's centre), its edges within 2.5 px (10-90 %), and its depth the
    objects' plane's (so a composite keeps it). Measured: IoU 0.985 (0.376 for the mirrored letter), scale 1.003, edge 0.78 px."""
    _, hologram, view, _ = imported
    camera = default_camera(hologram)
    alpha = view["Combined.A"]
    assert alpha.shape == camera.resolution[::-1]
    truth, (x, y) = truth_in_view(hologram, camera)
    seen = alpha > 0.5
    iou = (seen & truth).sum() / (seen | truth).sum()
    dot = (x - 0.25 * scans.LETTER_HEIGHT) ** 2 + (y + 0.3 * scans.LETTER_HEIGHT) ** 2 <= (
        0.09 * scans.LETTER_HEIGHT
    ) ** 2
    mirrored = scans.letter(-x, y)  # the letter as a mirrored view would show it
    rows, cols = np.indices(alpha.shape)

    def spacing(mask):
        f = mask & ~dot
        d = mask & dot
        return math.hypot(cols[d].mean() - cols[f].mean(), rows[d].mean() - rows[f].mean())

    scale = spacing(seen) / spacing(truth)
    edge = _edge_width(view["Combined.R"] / np.maximum(alpha, 1e-6) * seen, truth)
    depth = view["Depth.Z"][seen]
    flipped = (seen & mirrored).sum() / (seen | mirrored).sum()
    print(
        f"IoU {iou:.4f} (mirrored {flipped:.3f}), dot {seen[dot].mean():.3f} found, scale "
        f"{scale:.4f}, edge {edge:.2f} px, depth {depth.min():.6g}-{depth.max():.6g} m"
    )
    assert iou >= 0.95, iou
    assert seen[dot].mean() >= 0.9 and cols[dot].mean() > cols[truth].mean()  # on the right
    assert flipped <= 0.5, flipped
    assert abs(scale - 1) <= 0.01, scale
    assert edge <= 2.5, edge
    assert np.allclose(depth, camera.focus_distance, rtol=1e-5), (depth.min(), depth.max())


def _edge_width(luminance, truth) -> float:
    """The 10-90 % width [px] of the letter's stem's left edge, averaged over the stem's
    middle rows."""
    rows = np.nonzero(truth.any(1))[0]
    middle = rows[len(rows) // 3 : 2 * len(rows) // 3]
    left = int(np.nonzero(truth[middle].any(0))[0][0])
    profile = luminance[middle, left - 8 : left + 8].mean(0)
    profile = (profile - profile[:3].mean()) / (profile[-3:].mean() - profile[:3].mean())
    at = np.arange(profile.size, dtype=float)
    return float(np.interp(0.9, profile, at) - np.interp(0.1, profile, at))


def test_render_takes_the_written_hologram_and_frames_it(imported, tmp_path, capsys):
    """``render`` of the written hologram (objects on one stated plane) uses the camera that
    frames it, as import did; ``render`` of the scan itself without its optics says what it
    needs."""
    _, _, view, scan = imported
    status, _, err = run_cli(
        capsys,
        "render",
        scan.parent / "out" / "letter_scan_2048_holo.exr",
        "-o",
        tmp_path / "v.exr",
    )
    assert status == 0, err
    again = {k.split(".", 1)[1]: v for k, v in read_exr(tmp_path / "v.exr")[1].items()}
    assert np.array_equal(again["Combined.A"], view["Combined.A"])
    status, _, err = run_cli(capsys, "render", scan, "-o", tmp_path / "v.exr")
    assert (
        status == 2
        and "is a scan, not a Holo hologram: give --pitch, --wavelength, --distance" in err
    ), err


def test_millimetres_typed_as_metres_are_warned(imported):
    """A pitch of 0.00345 (3.45 µm in millimetres) and a distance of 50 (5 cm in
    millimetres) are real lengths that no camera scan has: warned with what they would be."""
    _, _, _, scan = imported
    with pytest.warns(UnitWarning, match="pitch 0.00345 m is 3.45 mm"):
        import_acquired(scan, pitch=0.00345, wavelength=633e-9, find_carrier=False)
    with pytest.warns(
        UnitWarning,
        match=r"distance 50 m is 7.08e\+03 times the hologram's "
        r"7.07 mm width: .* if it is in millimetres, pass 0.05",
    ):
        import_acquired(scan, pitch=3.45e-6, wavelength=633e-9, distance=50, sideband="upper")


@pytest.mark.parametrize("metric", ["brenner", "sobel_variance", "tamura"])
def test_autofocus_finds_the_distance_within_a_depth_of_focus(imported, metric):
    """The imported object wave, searched from 3 to 7 cm behind in 0.5 mm steps (on its
    band's own grid, :func:`decimate`): the 5 cm the scan was made at, within one depth of
    focus λ/NA² (NA = the band's sin θ = 0.024: 1.1 mm). Measured: 0 to 0.5 mm off."""
    _, hologram, _, _ = imported
    lam = hologram.wavelengths[0]
    wave, pitch = decimate(hologram.object_wave[0], pitch=hologram.pitch, band=hologram.band / lam)
    found = autofocus(
        wave,
        wavelength=lam,
        pitch=pitch,
        metric=metric,
        distances=-np.arange(0.03, 0.07 + 1e-9, 0.5e-3),
    )
    dof = depth_of_focus(lam, hologram.band / lam)
    print(
        f"{metric}: {-found.distance * 1e3:.2f} mm (depth of focus {dof * 1e3:.2f} mm, on "
        f"{wave.shape[0]}x{wave.shape[1]})"
    )
    assert abs(-found.distance - scans.DISTANCE) <= dof, found.distance


def test_a_complex_wave_file_imports_as_its_plane(tmp_path, capsys, rng):
    """An EXR of an acquired object wave (channels re, im: a phase-shifting setup's result)
    needs no filter: imported as it is, its objects on the plane at the distance."""
    from holo_core.io.image import write_exr

    wave = rng.normal(size=(32, 48)) + 1j * rng.normal(size=(32, 48))
    path = write_exr(tmp_path / "wave.exr", {"re": wave.real, "im": wave.imag})
    status, out, err = run_cli(
        capsys,
        "import",
        path,
        "--pitch",
        "5um",
        "--wavelength",
        "633",
        "--distance",
        "1cm",
        "-o",
        tmp_path / "h.exr",
        "--no-view",
    )
    assert status == 0, err
    h = read_hologram(tmp_path / "h.exr")
    assert h.encoding == "complex" and h.shape == (32, 48) and h.pitch == 5e-6
    assert np.allclose(h.object_wave[0], wave.astype(np.complex64))
    assert h.bounds[0][2] == h.bounds[1][2] == -0.01 and "complex object wave" in out
