"""A complex plate exported for real displays: phase-only patterns (double-phase, error
diffusion) and an amplitude pattern at an SLM's pitch, written as tiles, read back and viewed
through the core against the plate's own view."""

import logging
import math

import numpy as np
import pytest

from holo_core.io import display as tiles_io
from holo_core.phase import display as slm
from holo_core.plate.points import record_points
from holo_core.propagation import angular_spectrum, resample
from holo_core.scene.hologram import Hologram
from holo_core.validate import InputError

WAVELENGTH, PLATE_PITCH, DEPTH = 633e-9, 8e-6, -0.02
# twice the plate's sampling: the plate's band fills half the display's Nyquist frequency,
# what a 4f filter (and double-phase) needs
SLM = slm.Display(name="test-slm", resolution=(512, 512), pitch=4e-6, kind="phase", bit_depth=8)
CUT = 1 / (4 * SLM.pitch)  # the 4f filter: half the display's Nyquist frequency [cycles/m]


def plate(rng, shape=(256, 256)):
    """16 point emitters of random brightness 2 cm behind a 2 mm plate."""
    n = 16
    positions = np.c_[rng.uniform(-4e-4, 4e-4, (n, 2)), np.full(n, DEPTH)]
    return record_points(
        positions,
        rng.uniform(0.2, 1, (n, 1)),
        shape=shape,
        pitch=PLATE_PITCH,
        wavelengths=(WAVELENGTH,),
    )


def low_pass(u, pitch, cut=CUT):
    """The field through a 4f filter that keeps |f| < ``cut`` [cycles/m]."""
    fy, fx = np.fft.fftfreq(u.shape[0], pitch), np.fft.fftfreq(u.shape[1], pitch)
    return np.fft.ifft2(np.fft.fft2(u) * (fy[:, None] ** 2 + fx[None, :] ** 2 < cut**2))


def view(u, pitch):
    """The intensity on the points' plane, the wave propagated back from the display."""
    return (
        np.abs(
            angular_spectrum(
                np.asarray(u, np.complex64), wavelength=WAVELENGTH, pitch=pitch, distance=DEPTH
            )
        )
        ** 2
    )


def psnr(reference, image):
    """PSNR [dB] of ``image`` scaled (least squares) to ``reference``, peak = its maximum."""
    s = (reference * image).sum() / (image * image).sum()
    return 10 * math.log10(reference.max() ** 2 / np.mean((reference - s * image) ** 2))


@pytest.mark.parametrize("method, least", [("double-phase", 70), ("error-diffusion", 50)])
def test_an_exported_phase_hologram_views_like_the_plate(tmp_path, rng, method, least):
    """Exported as 8-bit tiles, read back as exp(i·phase), filtered at half the display's
    Nyquist frequency and propagated back 2 cm, the phase-only pattern shows the points as
    the complex plate does. Measured PSNR: double-phase 76.8 dB, error diffusion 53.1 dB."""
    h = plate(rng)
    path, _ = slm.export(
        h, SLM, tmp_path / "slm.json", distance=DEPTH, method=method, tile=(200, 300)
    )
    shown, layout = slm.read_phase_hologram(path)
    assert (layout["wavelength"], layout["distance"], layout["encoding"]) == (
        WAVELENGTH,
        DEPTH,
        method,
    )
    assert shown.shape == SLM.shape and shown.pitch == SLM.pitch
    assert np.allclose(np.abs(shown.object_wave), 1, atol=1e-6)
    reference = view(slm.display_field(h, SLM), SLM.pitch)
    measured = psnr(reference, view(low_pass(shown.object_wave[0], SLM.pitch), SLM.pitch))
    assert measured >= least, f"{method}: PSNR {measured:.1f} dB"


def test_error_diffusion_beats_plain_phase_quantisation(rng):
    """Through the same 4f filter, error diffusion's view is 10.6 dB better (measured 53.1
    against 42.5 dB) than that of exp(i·arg c), which drops the amplitude."""
    u = slm.display_field(plate(rng), SLM)
    reference = view(u, SLM.pitch)
    diffused, plain = (
        psnr(reference, view(low_pass(np.exp(1j * phase), SLM.pitch), SLM.pitch))
        for phase in (slm.error_diffusion(u), np.angle(u))
    )
    assert diffused >= plain + 8, f"error diffusion {diffused:.1f} dB, arg c {plain:.1f} dB"


def test_error_diffusion_matches_a_sample_by_sample_reference(rng):
    """The row-vectorised scan against a plain float64 Floyd–Steinberg loop over every
    sample, serpentine, written independently here (it checks the bookkeeping)."""
    c = rng.uniform(0, 1, (20, 17)) * np.exp(2j * np.pi * rng.uniform(size=(20, 17)))
    c[3, 4] = 0  # a zero sample becomes the phasor 1
    expected = np.angle(reference_diffusion(c / np.abs(c).max()))
    err = np.angle(np.exp(1j * (slm.error_diffusion(c) - expected)))
    assert np.abs(err).max() <= 1e-12, np.abs(err).max()


def reference_diffusion(c):
    c = c.astype(np.complex128).copy()
    h, w = c.shape
    out = np.zeros_like(c)
    for i in range(h):
        step = 1 if i % 2 == 0 else -1
        for j in range(w)[::step]:
            x = c[i, j]
            out[i, j] = x / abs(x) if abs(x) > 0 else 1
            e = x - out[i, j]
            for di, dj, weight in ((0, 1, 7), (1, -1, 3), (1, 0, 5), (1, 1, 1)):
                if i + di < h and 0 <= j + dj * step < w:
                    c[i + di, j + dj * step] += weight / 16 * e
    return out


def test_a_bias_pattern_gives_back_the_wave(tmp_path, rng):
    """t = (1 + Re(O·R*)/m)/2 lit by R holds O/(4m) at baseband, the bias and the twin at the
    carrier and twice it: the filtered product is the wave in the filter's band (measured
    1.3e-7 of its norm).
    Written as 16-bit tiles, the transmittance comes back within half a code."""
    h = plate(rng)
    screen = slm.Display(
        name="film", resolution=(512, 512), pitch=4e-6, kind="amplitude", bit_depth=16
    )
    path, t = slm.export(h, screen, tmp_path / "film.json", distance=DEPTH, fmt="tiff")
    assert t.min() >= 0 and t.max() <= 1
    back, layout = tiles_io.read_tiles(path)
    assert layout["encoding"] == "bias" and np.abs(back - t).max() <= 0.5 / 65535 + 1e-12
    u = slm.display_field(h, screen)
    x = (np.arange(512) - 255.5) * screen.pitch
    reference = np.exp(2j * np.pi * x / (4 * screen.pitch))[None, :]  # sin ϑ = λ/(4·pitch)
    got = low_pass(t * reference, screen.pitch)
    expected = low_pass(u, screen.pitch) / (4 * np.abs(u).max())  # the band the filter passes
    err = np.linalg.norm(got - expected) / np.linalg.norm(expected)
    assert err <= 1e-5, f"{err:.3g}"


def test_the_display_window_is_cut_around_the_plate_centre(rng):
    """At the plate's own pitch the display shows the plate's central samples exactly; at a
    finer pitch the window (with its margin) resamples as the whole plate does (measured
    2.7e-5 of the norm)."""
    h = plate(rng, shape=(512, 512))
    same = slm.Display(name="crop", resolution=(48, 64), pitch=PLATE_PITCH)
    assert np.array_equal(slm.display_field(h, same), h.object_wave[0, 224:288, 232:280])
    finer = slm.Display(name="fine", resolution=(60, 100), pitch=PLATE_PITCH / 2)
    whole = resample(
        h.object_wave[0], pitch=PLATE_PITCH, out_shape=finer.shape, out_pitch=finer.pitch
    )
    err = np.linalg.norm(slm.display_field(h, finer) - whole) / np.linalg.norm(whole)
    assert err <= 1e-4, f"{err:.3g}"


def test_a_wave_too_wide_for_the_filter_is_logged(rng, caplog):
    """A plate at the display's own pitch fills its whole Nyquist band: double-phase's
    filter would cut it, and the log says so with the plate pitch that would fit."""
    h = plate(rng, shape=(64, 64))
    with caplog.at_level(logging.WARNING, logger="holo_core.phase.display"):
        slm.display_field(h, slm.Display(name="same", resolution=(64, 64), pitch=PLATE_PITCH))
    assert "half the display's Nyquist" in caplog.text and "1.6e-05" in caplog.text


def test_presets():
    gaea = slm.display_preset("holoeye-gaea-4k")
    assert gaea.shape == (2160, 3840) and gaea.pitch == 3.74e-6 and gaea.kind == "phase"
    assert slm.DISPLAYS["print-1um"].kind == "amplitude"


@pytest.mark.parametrize(
    "settings, field",
    [
        ({"resolution": (0, 5)}, "display resolution"),
        ({"resolution": 3840}, "display resolution"),
        ({"pitch": 3.74}, "display pitch"),
        ({"kind": "binary"}, "display kind"),
        ({"bit_depth": 17}, "display bit_depth"),
        ({"name": ""}, "display name"),
    ],
)
def test_bad_displays_are_refused_naming_the_field(settings, field):
    with pytest.raises(InputError, match=field):
        slm.Display(**{"name": "x", "resolution": (64, 32), "pitch": 4e-6, **settings})


def test_bad_exports_are_refused_naming_the_field(tmp_path, rng):
    h = plate(rng, shape=(32, 32))
    small = slm.Display(name="s", resolution=(32, 32), pitch=PLATE_PITCH)
    cases = [
        ({"display": "no-such-slm"}, "display must be one of"),
        ({"method": "bias"}, "method"),
        ({"channel": 1}, "channel"),
        ({"distance": float("nan")}, "distance"),
        ({"path": tmp_path / "slm.png"}, "json"),
        ({"tile": (0, 1)}, "tile"),
        ({"fmt": "bmp"}, "fmt"),
    ]
    for change, field in cases:
        kw = {"display": small, "path": tmp_path / "slm.json", "distance": DEPTH, **change}
        with pytest.raises(InputError, match=field):
            slm.export(h, kw.pop("display"), kw.pop("path"), **kw)
    intensity_only = Hologram(
        intensity=np.ones((1, 8, 8), np.float32), pitch=PLATE_PITCH, wavelengths=(WAVELENGTH,)
    )
    with pytest.raises(InputError, match="no object_wave"):
        slm.for_display(intensity_only, small)
    assert not list(tmp_path.iterdir())


def test_bad_fields_are_refused_naming_the_field(tmp_path):
    c = np.full((4, 4), 0.5 + 0j)
    with pytest.raises(InputError, match="angle"):
        slm.amplitude_pattern(c, pitch=4e-6, wavelength=WAVELENGTH, angle=0.2)  # > 0.079 rad
    with pytest.raises(InputError, match="method"):
        slm.amplitude_pattern(c, pitch=4e-6, wavelength=WAVELENGTH, method="kinoform")
    with pytest.raises(InputError, match="all zero"):
        slm.error_diffusion(np.zeros((4, 4)))
    with pytest.raises(InputError, match="exceeds max_amplitude"):
        slm.error_diffusion(c, max_amplitude=0.25)
    with pytest.raises(InputError, match="finite"):
        slm.error_diffusion(np.full((4, 4), np.nan))
    path = tiles_io.write_tiles(
        tmp_path / "film.json",
        np.full((4, 4), 0.5),
        quantity="amplitude",
        pitch=4e-6,
        wavelength=WAVELENGTH,
        distance=DEPTH,
        encoding="bias",
    )
    with pytest.raises(InputError, match="not phases"):
        slm.read_phase_hologram(path)


@pytest.mark.parametrize("method", ["double-phase", "bias"])
def test_a_20000_squared_export_is_refused_with_its_size_before_the_plate_is_read(
    tmp_path, rng, monkeypatch, method
):
    """A 20000² pattern passed 10 GB before it failed; its arrays (measured 88 bytes per
    display sample for double-phase) are now counted first: 35.8 GiB against an 8 GiB budget
    is refused, nothing read, nothing written."""
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "8G")
    kind = "phase" if method == "double-phase" else "amplitude"
    big = slm.Display(name="wall", resolution=(20000, 20000), pitch=4e-6, kind=kind)
    h = plate(rng, (64, 64))
    read = []
    monkeypatch.setattr(slm, "resample", lambda *a, **k: read.append(1))
    with pytest.raises(
        InputError,
        match=r"a 20000x20000 pattern for the display 'wall' needs "
        r"3\d\.\d GiB of memory; \S+ GiB is available",
    ):
        slm.export(h, big, tmp_path / "wall.json", distance=DEPTH, method=method)
    assert not read and not list(tmp_path.iterdir())


def test_an_exported_carrier_plate_views_like_its_physical_field(tmp_path, rng):
    """A plate stored against its zone's carrier (16 emitters 20 cm behind, a zone 8 mm wide
    30 cm in front; B 203 x 201 samples 20.5 µm apart, at its band's Nyquist pitch) is exported
    to a 1024² display at 4 µm as its physical field there (physical_field's), double-phase
    encoded, read back, filtered at half the display's Nyquist frequency and propagated back
    to the emitters: it shows them as the field the export encoded does (measured PSNR
    96.5 dB: the encoding's error), and as the physical field summed directly (float64 NumPy,
    the same emitters and windows towards the zone: 75.6 dB). The two fields differ by
    7.5e-2: the samples' own aliasing (a footprint of about 100 samples, its soft rim a few;
    test_carrier.py), which the display shows as faint speckle around the points."""
    from accuracy import rel_err
    from zone_reference import carrier_plate, object_wave

    from holo_core.plate.carrier import physical_field
    from holo_core.plate.zone_sum import ZoneEmitters
    from holo_core.scene.plate import ViewingZone

    display, depth, n = (
        slm.Display(
            name="test-slm-4mm", resolution=(1024, 1024), pitch=4e-6, kind="phase", bit_depth=8
        ),
        -0.2,
        16,
    )
    em = ZoneEmitters(
        position=np.c_[rng.uniform(-4e-4, 4e-4, (n, 2)), np.full(n, depth)],
        amplitude=np.sqrt(rng.uniform(0.2, 1, (n, 1))) * np.exp(2j * np.pi * rng.random((n, 1))),
        visibility=np.full(n, -1, np.int32),
        table=np.zeros((0, 3, 3), np.uint8),
        grid=((-4e-3, 4e-3), (-4e-3, 4e-3)),
    )
    zone = ViewingZone(centre=(0.0, 0.0, 0.3), half_extents=(0.004, 0.004, 0.001))
    h = carrier_plate(em, zone, WAVELENGTH)
    path, _ = slm.export(h, display, tmp_path / "slm.json", distance=depth)
    shown, _ = slm.read_phase_hologram(path)
    exported = slm.display_field(h, display)
    xs = (np.arange(1024) - 511.5) * display.pitch
    region = physical_field(h, pitch=display.pitch, region=(xs[0], xs[0], xs[-1], xs[-1]))
    assert np.array_equal(region.samples, exported)
    direct = object_wave(em, zone, WAVELENGTH, xs, xs)[0]
    cut = 1 / (4 * display.pitch)

    def seen(u):
        u = low_pass(u, display.pitch, cut)
        return (
            np.abs(
                angular_spectrum(
                    np.asarray(u, np.complex64),
                    wavelength=WAVELENGTH,
                    pitch=display.pitch,
                    distance=depth,
                )
            )
            ** 2
        )

    shown_view = seen(shown.object_wave[0])
    encoded, summed = psnr(seen(exported), shown_view), psnr(seen(direct), shown_view)
    print(
        f"{h.shape}: against the field encoded {encoded:.1f} dB, against the direct sum "
        f"{summed:.1f} dB; the fields differ by {rel_err(exported, direct):.2e}"
    )
    assert encoded >= 85 and summed >= 65, (encoded, summed)
