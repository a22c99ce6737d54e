"""Bad input gets an InputError naming the argument and its allowed range.

The tables cover, across the public API, the ways bad input goes wrong: unclean exception
types (ZeroDivisionError, TypeError, IndexError, a plain ValueError naming no field), results
silently empty, NaN or rounded, and misleading messages. Each bad call must raise
:class:`InputError` whose message names the field.
"""

import math

import numpy as np
import pytest

from holo_core import validate
from holo_core.camera import render_camera
from holo_core.io.acquired import read_acquired
from holo_core.optics.pupil import Pupil
from holo_core.plate import Reference, reconstruct, record_hologram, record_points, render_view
from holo_core.plate.sampling import choose
from holo_core.plate.view import EmptyViewWarning
from holo_core.propagation import (
    angular_spectrum,
    fraunhofer,
    fresnel,
    propagate_to_plane,
    rayleigh_sommerfeld,
    resample,
    tilt,
)
from holo_core.scene import Camera, Hologram, Mesh, Plate, look_at, sample_points
from holo_core.validate import InputError

GOOD = {"wavelength": 633e-9, "pitch": 1e-6, "distance": 1e-3}
FIELD = np.ones((16, 16), np.complex64)
NAN, INF = float("nan"), float("inf")
TRIANGLE = Mesh(
    vertices=np.array([[0, 0, -1], [0.1, 0, -1], [0, 0.1, -1.0]]), triangles=np.array([[0, 1, 2]])
)
PLATE = Plate(matrix_world=np.eye(4), width=0.01, height=0.01)
FAR = Camera(matrix_world=look_at((0, 0, 0.5), (0, 0, -1)), resolution=(8, 8))  # sees TRIANGLE


@pytest.fixture(scope="module")
def h():
    """A point 3 mm behind a 32 µm plate."""
    return record_points(
        [[0, 0, -3e-3]], [[1.0]], shape=(32, 32), pitch=1e-6, wavelengths=(633e-9,)
    )


def camera(**changes):
    return Camera(
        **{
            "matrix_world": look_at((0, 0, 4e-3), (0, 0, -3e-3)),
            "lens": 50,
            "sensor_width": 50 * 16 * 4e-3,
            "resolution": (8, 8),
            **changes,
        }
    )


def turn(degrees):
    """A rotation about y by ``degrees``."""
    a = math.radians(degrees)
    return np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])


def hologram(**changes):
    return Hologram(
        **{
            "intensity": np.ones((1, 4, 4), np.float32),
            "wavelengths": (633e-9,),
            "pitch": 8e-6,
            **changes,
        }
    )


def mesh(**changes):
    return Mesh(**{"vertices": np.eye(3), "triangles": np.array([[0, 1, 2]]), **changes})


def points(**changes):
    return record_points(
        **{
            "positions": [[0, 0, -3e-3]],
            "colours": [[1.0]],
            "shape": (16, 16),
            "pitch": 1e-6,
            "wavelengths": (633e-9,),
            **changes,
        }
    )


def asm(**changes):
    return angular_spectrum(**{"field": FIELD, **GOOD, **changes})


# (call, the field whose allowed values the message states: "<field> must ..."); ``call``
# takes the fixture hologram
BAD_CALLS = {
    # propagation: empty, non-numeric and absurd arguments
    "asm field 0x0 (was ZeroDivisionError)": (lambda h: asm(field=np.zeros((0, 0))), "field"),
    "asm field None": (lambda h: asm(field=None), "field"),
    "asm wavelength 1e-300 (was ZeroDivisionError)": (
        lambda h: asm(wavelength=1e-300),
        "wavelength",
    ),
    "asm wavelength 1e300 (was OverflowError)": (lambda h: asm(wavelength=1e300), "wavelength"),
    "asm pitch nan": (lambda h: asm(pitch=NAN), "pitch"),
    "asm distance inf": (lambda h: asm(distance=INF), "distance"),
    "asm offset 'x'": (lambda h: asm(offset="x"), "offset"),
    "asm padding nan": (lambda h: asm(padding=NAN), "padding"),
    "fresnel pitch 0": (lambda h: fresnel(FIELD, **{**GOOD, "pitch": 0}), "pitch"),
    "fraunhofer pitch 1e300 (was OverflowError)": (
        lambda h: fraunhofer(FIELD, wavelength=633e-9, pitch=1e300, distance=1.0),
        "pitch",
    ),
    "rayleigh_sommerfeld field nan (was AttributeError)": (
        lambda h: rayleigh_sommerfeld(NAN, **GOOD),
        "field",
    ),
    "rayleigh_sommerfeld field 0x0": (
        lambda h: rayleigh_sommerfeld(np.zeros((0, 4)), **GOOD),
        "field",
    ),
    "rayleigh_sommerfeld out_pitch 1e-300": (
        lambda h: rayleigh_sommerfeld(FIELD, **GOOD, out_pitch=1e-300),
        "out_pitch",
    ),
    "resample out_pitch 1e-300": (
        lambda h: resample(FIELD, pitch=1e-6, out_shape=(4, 4), out_pitch=1e-300),
        "out_pitch",
    ),
    "tilt rotation 'x' (was ValueError naming no field)": (
        lambda h: tilt(FIELD, wavelength=633e-9, pitch=1e-6, rotation="x"),
        "rotation",
    ),
    "tilt wavelength 1e-300 (was ZeroDivisionError)": (
        lambda h: tilt(FIELD, wavelength=1e-300, pitch=1e-6, rotation=np.eye(3)),
        "wavelength",
    ),
    "propagate_to_plane position 'x'": (
        lambda h: propagate_to_plane(
            FIELD, wavelength=633e-9, pitch=1e-6, rotation=np.eye(3), position="x"
        ),
        "position",
    ),
    # recording: seeds, arrays and stored fields, all before the work
    "record_points seed nan (was TypeError)": (lambda h: points(seed=NAN), "seed"),
    "record_points seed -1 (was ValueError naming no field)": (lambda h: points(seed=-1), "seed"),
    "record_points seed 1.5": (lambda h: points(seed=1.5), "seed"),
    "record_points positions None (was TypeError)": (lambda h: points(positions=None), "positions"),
    "record_points positions (2,)": (lambda h: points(positions=[1.0, 2.0]), "positions"),
    "record_points colours 'x'": (lambda h: points(colours="x"), "colours"),
    "record_points colours nan": (lambda h: points(colours=[[NAN]]), "colours"),
    "record_points colours 1e300 (was RuntimeError)": (
        lambda h: points(colours=[[1e300]]),
        "colours",
    ),
    "record_points phases of 2": (lambda h: points(phases=[0.0, 1.0]), "phases"),
    "record_points wavelengths 1e-300": (lambda h: points(wavelengths=(1e-300,)), "wavelengths"),
    "record_points pitch 1e-300": (lambda h: points(pitch=1e-300), "pitch"),
    "record_points band 1.5": (lambda h: points(band=1.5), "band"),
    "record_points band nan": (lambda h: points(band=NAN), "band"),
    "record_points point_density -1": (lambda h: points(point_density=-1.0), "point_density"),
    "record_points channels Q": (lambda h: points(channels=("Q",)), "channels"),
    "record_points plate singular": (lambda h: points(plate=np.zeros((4, 4))), "plate rotation"),
    "record_points reference 'x'": (lambda h: points(reference="x"), "reference"),
    "record_points shape 0x0": (lambda h: points(shape=(0, 0)), "shape"),
    "record_hologram seed nan": (
        lambda h: record_hologram(([[0, 0, -0.05]], [[1, 1, 1]]), plate=PLATE, seed=NAN),
        "seed",
    ),
    "record_hologram plate None": (
        lambda h: record_hologram(([[0, 0, -0.05]], [[1, 1, 1]]), plate=None),
        "plate",
    ),
    "choose max_resolution nan (was 'cannot convert float NaN to integer')": (
        lambda h: choose((0.01, 0.01), [[0, 0, -0.05]], max_resolution=NAN),
        "max_resolution",
    ),
    "choose wavelength nan (was 'cannot convert float NaN to integer')": (
        lambda h: choose((0.01, 0.01), [[0, 0, -0.05]], wavelength=NAN),
        "wavelength",
    ),
    "choose points 'x'": (lambda h: choose((0.01, 0.01), "x"), "points"),
    "Reference angle nan": (lambda h: Reference(angle=NAN), "angle"),
    # reconstruction and views
    "reconstruct colour 1.5 (was IndexError)": (lambda h: reconstruct(_three(h), 1.5), "colour"),
    "reconstruct colour 1e-300": (lambda h: reconstruct(h, 1e-300), "colour"),
    "reconstruct colour None (was TypeError)": (lambda h: reconstruct(h, None), "colour"),
    "reconstruct colour -1": (lambda h: reconstruct(h, -1), "colour"),
    "reconstruct hologram None (was AttributeError)": (lambda h: reconstruct(None), "hologram"),
    "render_view supersample 1.5 (was run as 1)": (
        lambda h: render_view(h, camera(), supersample=1.5),
        "supersample",
    ),
    "render_view supersample 0": (lambda h: render_view(h, camera(), supersample=0), "supersample"),
    "render_view supersample 1e300 (was OverflowError)": (
        lambda h: render_view(h, camera(), supersample=1e300),
        "supersample",
    ),
    "render_view camera None (was AttributeError)": (lambda h: render_view(h, None), "camera"),
    "render_view holograms None (was TypeError)": (
        lambda h: render_view(None, camera()),
        "holograms",
    ),
    "render_view holograms []": (lambda h: render_view([], camera()), "holograms"),
    "render_view aperture 'x'": (lambda h: render_view(h, camera(), aperture="x"), "aperture"),
    "render_view exposure nan": (lambda h: render_view(h, camera(), exposure=NAN), "exposure"),
    "render_camera supersample 1.5 (was run as 1)": (
        lambda h: render_camera(TRIANGLE, FAR, supersample=1.5),
        "supersample",
    ),
    "render_camera seed nan (was TypeError)": (
        lambda h: render_camera(TRIANGLE, FAR, seed=NAN),
        "seed",
    ),
    "render_camera samples 2.5": (lambda h: render_camera(TRIANGLE, FAR, samples=2.5), "samples"),
    "render_camera camera None": (lambda h: render_camera(TRIANGLE, None), "camera"),
    "render_camera meshes 1.0 (was TypeError)": (lambda h: render_camera(1.0, FAR), "meshes"),
    "render_camera points 'x'": (lambda h: render_camera(points="x", camera=FAR), "points"),
    "render_camera exposure -1": (
        lambda h: render_camera(TRIANGLE, FAR, exposure=-1.0),
        "exposure",
    ),
    "read_acquired wavelength 1e-300": (
        lambda h: read_acquired("missing.png", pitch=5e-6, wavelength=1e-300),
        "wavelength",
    ),
    # scene nouns
    "Hologram pitch 1e-300 (rendered all-NaN)": (lambda h: hologram(pitch=1e-300), "pitch"),
    "Hologram wavelengths scalar (was TypeError)": (
        lambda h: hologram(wavelengths=633e-9),
        "wavelengths",
    ),
    "Hologram wavelengths ()": (lambda h: hologram(wavelengths=()), "wavelengths"),
    "Hologram reference_amplitudes 0 (was NaN later)": (
        lambda h: hologram(reference_amplitudes=(0.0,)),
        "reference_amplitudes",
    ),
    "Hologram band 1 (unreadable once written)": (lambda h: hologram(band=1.0), "band"),
    "Hologram bounds nan": (lambda h: hologram(bounds=np.full((2, 3), NAN)), "bounds"),
    "Hologram object_wave shape": (
        lambda h: hologram(object_wave=np.ones((1, 2, 2))),
        "object_wave",
    ),
    "Hologram channels 5 (was TypeError)": (lambda h: hologram(channels=5), "channels"),
    "Mesh colours nan (flowed on)": (lambda h: mesh(colours=np.full((3, 3), NAN)), "colours"),
    "Mesh colours of 2 vertices": (lambda h: mesh(colours=np.ones((2, 3))), "colours"),
    "Mesh colours negative": (lambda h: mesh(colours=-np.ones((3, 3))), "colours"),
    "Mesh triangles float (flowed on)": (
        lambda h: mesh(triangles=np.array([[0, 1, 2.5]])),
        "triangles",
    ),
    "Mesh triangles out of range": (lambda h: mesh(triangles=[[0, 1, 3]]), "triangles"),
    "Mesh of no triangle": (lambda h: mesh(triangles=np.zeros((0, 3), int)), "triangles"),
    "Mesh empty": (
        lambda h: mesh(vertices=np.zeros((0, 3)), triangles=np.zeros((0, 3), int)),
        "triangles",
    ),
    "Mesh vertices 'x'": (lambda h: mesh(vertices="x"), "vertices"),
    "Mesh uvs (3, 3)": (lambda h: mesh(uvs=np.zeros((3, 3))), "uvs"),
    "Mesh texture inf": (lambda h: mesh(texture=np.full((2, 2, 3), INF)), "texture"),
    "sample_points seed nan (was TypeError)": (
        lambda h: sample_points(TRIANGLE, 0.01, seed=NAN),
        "seed",
    ),
    "sample_points max_points 1.5": (
        lambda h: sample_points(TRIANGLE, 0.01, max_points=1.5),
        "max_points",
    ),
    "look_at eye nan (said 'needs target != eye')": (
        lambda h: look_at((NAN, 0, 1), (0, 0, 0)),
        "eye",
    ),
    "look_at target 'x'": (lambda h: look_at((0, 0, 1), "x"), "target"),
    "look_at up zero": (lambda h: look_at((0, 0, 1), (0, 0, 0), up=(0, 0, 0)), "up"),
    "Camera resolution (nan, 8)": (lambda h: camera(resolution=(NAN, 8)), "resolution"),
    "Plate width 0": (lambda h: Plate(matrix_world=np.eye(4), width=0, height=1), "width"),
    "Pupil diameter nan": (lambda h: Pupil(diameter=NAN), "diameter"),
}


def _three(h):
    """``h`` with three colours, where 1.5 passed the range check and then failed to index."""
    return Hologram(
        intensity=np.repeat(h.intensity, 3, 0), wavelengths=h.wavelengths * 3, pitch=h.pitch
    )


@pytest.mark.parametrize("case", BAD_CALLS)
def test_a_bad_call_raises_input_error_naming_the_field(h, case):
    call, field = BAD_CALLS[case]
    with pytest.raises(InputError) as raised:
        call(h)
    assert f"{field} must" in str(raised.value), (
        f"{case}: says not what {field!r} must be: {raised.value}"
    )


@pytest.mark.parametrize("degrees", [0, 10, 20, 30, 36, 37, 45, 60, 89.9, 90, 120, 180])
def test_a_tilt_is_never_silently_empty(degrees):
    """A tilted plane either receives light or is refused: at pitch 1 µm and λ 633 nm both
    grids hold directions within 18.45° of their normals, so no light reaches a plane tilted
    by 36.9° or more (a 90° tilt returned zeros)."""
    field = np.random.default_rng(1).normal(size=(32, 32)).astype(np.complex64)
    reach = 2 * math.degrees(math.asin(633e-9 / 2e-6))
    if degrees >= reach:
        with pytest.raises(
            InputError,
            match=rf"rotation tilts .* by {degrees:.1f}°.* less "
            rf"than {reach:.1f}°",
        ):
            tilt(field, wavelength=633e-9, pitch=1e-6, rotation=turn(degrees))
        return
    out = tilt(field, wavelength=633e-9, pitch=1e-6, rotation=turn(degrees))
    share = float(np.sum(np.abs(out) ** 2) / np.sum(np.abs(field) ** 2))
    assert share > 1e-3, f"{degrees}° kept {share:.2e} of the energy"


@pytest.mark.parametrize("degrees", [0, 10, 25, 45, 70, 89])
def test_a_view_is_never_silently_black(h, degrees):
    """A camera around the plate either sees light or is told the view is black."""
    import warnings

    a = math.radians(degrees)
    cam = camera(
        matrix_world=look_at(8e-3 * np.array([math.sin(a), 0, math.cos(a)]), (0, 0, -3e-3))
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        view = render_view(h, cam)
    black = [w for w in caught if issubclass(w.category, EmptyViewWarning)]
    peak = float(view.rgb.max())
    assert (peak > 0) != bool(black), f"{degrees}°: peak {peak:.3g}, warned {bool(black)}"


@pytest.mark.parametrize(
    "field, changes, message",
    [
        (np.full((8, 8), np.nan), {}, "field must be finite"),
        (np.ones((8, 8)) * np.inf, {}, "field must be finite"),
        (np.ones(4), {}, "field must be a 2-D array"),  # (..., H, W) is a batch
        (
            FIELD,
            {"wavelength": 0.0},
            r"wavelength must be in \[1e-13, 0.01\] \[m\] \(.*\); got 0.0",
        ),
        (FIELD, {"wavelength": -5e-7}, r"wavelength must be in \[1e-13, 0.01\] \[m\] \(.*\)"),
        (FIELD, {"pitch": 0}, r"pitch must be in \[1e-12, 0.01\] \[m\] \(.*\); got 0"),
        (FIELD, {"pitch": float("nan")}, r"pitch must be finite"),
        (FIELD, {"padding": 0.5}, r"padding must be >= 1"),
        (FIELD, {"padding": 100}, r"padding must be in \[1, 16\]"),
        (FIELD, {"offset": (1.0,)}, r"offset must be a pair"),
    ],
)
def test_angular_spectrum_rejects(field, changes, message):
    with pytest.raises(ValueError, match=message):
        angular_spectrum(field, **{**GOOD, **changes})


def test_device_arrays_are_checked_too(rt):
    bad = np.ones((8, 8), np.complex64)
    bad[3, 4] = np.nan
    with pytest.raises(ValueError, match="field must be finite"):
        angular_spectrum(rt.to_device(bad), **GOOD)
    with pytest.raises(ValueError, match="field must be finite"):
        tilt(rt.to_device(bad), wavelength=633e-9, pitch=1e-6, rotation=np.eye(3))
    with pytest.raises(InputError, match="field must hold at least 1x1 samples"):
        angular_spectrum(rt.to_device(np.zeros((0, 4), np.complex64)), **GOOD)


def test_other_stages_reject_bad_settings():
    with pytest.raises(ValueError, match="distance must be non-zero"):
        rayleigh_sommerfeld(FIELD, wavelength=633e-9, pitch=1e-6, distance=0.0)
    with pytest.raises(ValueError, match="rotation must be a rotation"):
        tilt(FIELD, wavelength=633e-9, pitch=1e-6, rotation=np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match=r"out_shape must be a pair of integers >= 1"):
        resample(FIELD, pitch=1e-6, out_shape=(0, 4), out_pitch=1e-6)
    with pytest.raises(ValueError, match=r"out_pitch must be in \[1e-12, 0.01\] \[m\] \(.*\)"):
        resample(FIELD, pitch=1e-6, out_shape=(4, 4), out_pitch=-1)


@pytest.mark.parametrize(
    "value, text",
    [
        (np.float64(633.0), "633.0"),
        (np.float32(0.1), "0.1"),
        (np.int64(-3), "-3"),
        (np.bool_(True), "True"),
        ([np.float64(1.5), 2], "[1.5, 2]"),
        ((np.float64(2.0),), "(2.0,)"),
        ("f", "'f'"),
        (None, "None"),
    ],
)
def test_numpy_numbers_are_named_as_numbers(value, text):
    """Errors name a NumPy number as the number it is, also under NumPy 2, whose repr writes
    np.float64(633.0) (the nanometre wavelength's refusal read so there)."""
    assert validate.shown(value) == text
    with pytest.raises(InputError, match=r"got -2\.5$"):
        validate.positive("pitch", np.float64(-2.5))
