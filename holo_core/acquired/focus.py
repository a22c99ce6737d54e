"""Numerical refocus of an acquired wave and autofocus over a range of distances.

:func:`refocus` carries the object wave by the angular spectrum (the project's, band-limited
and exact for any angle) to any distance; :func:`autofocus` scores the amplitude of the wave at
each distance with a focus metric and returns the best. The metrics are the ones DHM tools
offer (PyHoloscope, pyDHM; Langehanenberg et al. 2008), each on the amplitude A = |u|:

- ``brenner``: Σ (A(x+2) − A(x))² along rows and columns (Brenner et al. 1976);
- ``sobel_variance``: the variance of the Sobel gradient's magnitude (Tenengrad variance);
- ``gradient``: Σ |∇A|² (Tenengrad);
- ``variance``: var(A)/mean(A), the normalised variance;
- ``tamura``: √(std(A)/mean(A)), Tamura's coefficient;
- ``peak``: the peak intensity max |u|².

:func:`decimate` puts a band-limited wave on the coarsest grid that holds it first, which
makes a search over many distances cheap. An object that shows in amplitude is sharpest where
they are largest (``extremum='max'``); a pure phase object is flattest in focus
(``extremum='min'``). Distances are propagation distances [m]: an object behind the hologram
(z < 0) is brought into focus by a negative one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import validate
from ..propagation import angular_spectrum
from ..validate import InputError, shown


def _brenner(a):
    return float(np.sum((a[:, 2:] - a[:, :-2]) ** 2) + np.sum((a[2:] - a[:-2]) ** 2))


def _sobel(a):
    gx = (a[:-2, 2:] + 2 * a[1:-1, 2:] + a[2:, 2:]) - (a[:-2, :-2] + 2 * a[1:-1, :-2] + a[2:, :-2])
    gy = (a[2:, :-2] + 2 * a[2:, 1:-1] + a[2:, 2:]) - (a[:-2, :-2] + 2 * a[:-2, 1:-1] + a[:-2, 2:])
    return np.hypot(gx, gy)


def _gradient(a):
    return float(np.sum(np.diff(a, axis=1) ** 2) + np.sum(np.diff(a, axis=0) ** 2))


def _ratio(top, bottom):
    return float(top / bottom) if bottom > 0 else 0.0


METRICS = {
    "brenner": _brenner,
    "sobel_variance": lambda a: float(np.var(_sobel(a))),
    "gradient": _gradient,
    "variance": lambda a: _ratio(np.var(a), np.mean(a)),
    "tamura": lambda a: float(np.sqrt(_ratio(np.std(a), np.mean(a)))),
    "peak": lambda a: float(np.max(a) ** 2),
}
"""The focus metrics by name, each a function of the amplitude A = |u| (a float64 (H, W)
array) to a float, larger where sharper for an object that shows in amplitude: 'brenner'
Σ (A(x+2) − A(x))² along rows and columns; 'sobel_variance' the variance of the Sobel
gradient's magnitude; 'gradient' Σ |∇A|² (Tenengrad); 'variance' var(A)/mean(A); 'tamura'
√(std(A)/mean(A)); 'peak' max |u|². :func:`focus_metric` and :func:`autofocus` take a name
from it."""


@dataclass(frozen=True, slots=True)
class Focus:
    """The result of :func:`autofocus`.

    Parameters
    ----------
    distance : float
        The best of ``distances`` [m] (a propagation distance: negative towards an object
        behind the hologram).
    distances : (D,) float64 ndarray
        Every distance tried [m].
    scores : (D,) float64 ndarray
        Each distance's score under ``metric`` (dimensionless, the metric's own scale).
    metric : str
        The name in :data:`METRICS`.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.acquired import Focus
    >>> f = Focus(np.float64(-2e-3), np.array([-3e-3, -2e-3]), np.array([1.0, 2.0]), "peak")
    >>> f.distance, f.metric
    (-0.002, 'peak')
    """

    distance: float
    distances: np.ndarray
    scores: np.ndarray
    metric: str


def focus_metric(wave, metric: str = "brenner") -> float:
    """The focus metric of a wave's amplitude.

    Parameters
    ----------
    wave : (H, W) array
        A complex wave (or a real amplitude); its amplitude A = |u| is scored.
    metric : str
        One of :data:`METRICS` ('brenner', 'sobel_variance', 'gradient', 'variance',
        'tamura', 'peak').

    Returns
    -------
    float
        The score (dimensionless, on the metric's own scale; larger is sharper for objects
        that show in amplitude).

    Raises
    ------
    InputError
        Where ``metric`` is unknown.

    Examples
    --------
    One bright sample: its peak intensity, and Brenner's sum of squared two-sample
    differences (1 on each side, along rows and along columns):

    >>> import numpy as np
    >>> from holo_core.acquired import focus_metric
    >>> a = np.zeros((32, 32)); a[16, 16] = 1
    >>> focus_metric(a, "peak"), focus_metric(a, "brenner")
    (1.0, 4.0)
    """
    validate.choice("metric", metric, tuple(METRICS))
    return METRICS[metric](np.abs(np.asarray(wave)).astype(np.float64))


@validate.public
def refocus(wave, *, wavelength, pitch, distance) -> np.ndarray:
    """The wave a distance away, by the angular spectrum.

    Parameters
    ----------
    wave : (H, W) complex array
        An object wave (e.g. :func:`~holo_core.acquired.sideband`'s).
    wavelength : float
        Wavelength λ [m].
    pitch : float
        Sample spacing [m].
    distance : float or sequence of float
        Propagation distance [m]; negative: back towards an object behind the hologram. A
        sequence gives a focus stack.

    Returns
    -------
    (H, W) or (D, H, W) complex64 ndarray
        The wave at ``distance``, or at each of the D distances.

    Raises
    ------
    InputError
        Where a length is not finite and > 0 (``wavelength``, ``pitch``) or a distance is
        out of range, naming it.

    Notes
    -----
    :func:`holo_core.angular_spectrum` (Eq. 14), band-limited and exact at any angle.

    Examples
    --------
    Forward by 0.2 mm and back returns the wave (a Gaussian well inside the grid):

    >>> import numpy as np
    >>> from holo_core.acquired import refocus
    >>> y, x = np.mgrid[-32:32, -32:32] * 2e-6
    >>> g = np.exp(-(x**2 + y**2) / (2 * (10e-6) ** 2))
    >>> there = refocus(g, wavelength=633e-9, pitch=2e-6, distance=2e-4)
    >>> back = refocus(there, wavelength=633e-9, pitch=2e-6, distance=-2e-4)
    >>> bool(np.abs(back - g).max() < 1e-5), there.dtype
    (True, dtype('complex64'))
    """
    return angular_spectrum(
        np.asarray(wave, np.complex64), wavelength=wavelength, pitch=pitch, distance=distance
    )


@validate.public
def autofocus(
    wave, *, wavelength, pitch, distances, metric="brenner", extremum="max", region=None
) -> Focus:
    """Find the distance among ``distances`` at which ``wave`` is sharpest by ``metric``.

    Parameters
    ----------
    wave : (H, W) complex array
        An object wave (e.g. :func:`~holo_core.acquired.sideband`'s).
    wavelength : float
        Wavelength λ [m].
    pitch : float
        Sample spacing [m].
    distances : sequence of float
        Propagation distances [m] to try, one plane at a time (memory: one plane).
    metric : str
        One of :data:`~holo_core.acquired.METRICS`.
    extremum : 'max' or 'min'
        Sharpest at the largest score (objects that show in amplitude) or the smallest
        (pure phase objects).
    region : (row0, row1, col0, col1), optional
        The window the metric reads (default: the whole plane).

    Returns
    -------
    Focus
        ``distance`` [m] (the best of ``distances``), the ``distances`` [m] tried, their
        ``scores`` and the ``metric``.

    Raises
    ------
    InputError
        Where ``distances`` is empty or not finite, ``metric`` or ``extremum`` is unknown, or
        ``region`` does not lie in the plane (at least 3 × 3).

    Notes
    -----
    Each distance is reached by the angular spectrum (Eq. 14); an object behind the hologram
    (z < 0) is brought into focus by a negative distance.

    Examples
    --------
    The object wave of one point 2 mm behind the plate focuses at −2 mm:

    >>> import numpy as np
    >>> from holo_core import autofocus, record_points
    >>> h = record_points(np.array([[0.0, 0.0, -2e-3]]), np.array([[1.0]]), shape=(64, 64),
    ...                   pitch=2e-6, wavelengths=(633e-9,))
    >>> f = autofocus(h.object_wave[0], wavelength=633e-9, pitch=2e-6,
    ...               distances=[-3e-3, -2e-3, -1e-3])
    >>> f.distance
    -0.002
    """
    u = validate.host_field("wave", wave).astype(np.complex64)
    distances = np.asarray(distances, np.float64).reshape(-1)
    if not distances.size or not np.isfinite(distances).all():
        raise InputError(
            f"distances must be a non-empty sequence of finite numbers [m]; got {distances!r}"[:300]
        )
    validate.choice("metric", metric, tuple(METRICS))
    validate.choice("extremum", extremum, ("max", "min"))
    rows = _region(region, u.shape)
    scores = np.array(
        [
            focus_metric(
                refocus(u, wavelength=wavelength, pitch=pitch, distance=float(z))[rows], metric
            )
            for z in distances
        ]
    )
    best = int(np.argmax(scores) if extremum == "max" else np.argmin(scores))
    return Focus(distance=float(distances[best]), distances=distances, scores=scores, metric=metric)


def _region(region, shape):
    if region is None:
        return (slice(None), slice(None))
    try:
        r0, r1, c0, c1 = (validate.integer("region", v, 0) for v in region)
    except (TypeError, ValueError):
        raise InputError(f"region must be (row0, row1, col0, col1); got {shown(region)}") from None
    if not (r0 < r1 <= shape[0] and c0 < c1 <= shape[1]) or min(r1 - r0, c1 - c0) < 3:
        raise InputError(
            f"region must lie in the {shape[0]}x{shape[1]} plane, at least 3x3; got {shown(region)}"
        )
    return (slice(r0, r1), slice(c0, c1))


@validate.public
def decimate(wave, *, pitch, band) -> tuple[np.ndarray, float]:
    """A band-limited wave on the coarsest grid that still holds its band.

    Its spectrum is cropped to ±``band`` (and 2 bins) about zero, as a band-limited wave (a
    sideband filter's) allows, exactly. Refocusing and autofocus on it cost (band·2·pitch)²
    of the full grid's.

    Parameters
    ----------
    wave : (H, W) complex array
        The wave, band-limited to ``band``.
    pitch : float
        Its sample spacing [m].
    band : float
        Its highest spatial frequency [1/m], > 0.

    Returns
    -------
    wave : (h, w) complex64 ndarray
        The wave on the coarser grid, its amplitudes unchanged.
    pitch : float
        The coarser grid's sample spacing [m] (one for both axes).

    Raises
    ------
    InputError
        Where ``pitch`` or ``band`` is not finite and > 0.

    Examples
    --------
    A plane wave of 31.25 mm⁻¹ on 64 × 64 samples of 2 µm keeps its phase step on 16 × 16:

    >>> import numpy as np
    >>> from holo_core.acquired import decimate
    >>> x = np.arange(64) * 2e-6
    >>> wave = np.tile(np.exp(2j * np.pi * 31250 * x), (64, 1))
    >>> small, pitch = decimate(wave, pitch=2e-6, band=4e4)
    >>> small.shape, pitch
    ((16, 16), 8e-06)
    >>> round(float(np.angle(small[0, 1] / small[0, 0])), 4)   # 2π·31250·8 µm
    1.5708
    """
    u = validate.host_field("wave", wave)
    pitch = validate.pitch("pitch", pitch)
    band = validate.positive("band", band, "1/m")
    rows, cols = u.shape
    keep = [min(n, 2 * math.ceil(band * n * pitch) + 4) for n in (rows, cols)]
    if keep[0] * cols != keep[1] * rows:  # one pitch for both axes: the larger ratio
        ratio = max(keep[0] / rows, keep[1] / cols)
        keep = [min(n, 2 * math.ceil(ratio * n / 2)) for n in (rows, cols)]
    spectrum = np.fft.fftshift(np.fft.fft2(u))
    r0, c0 = (rows - keep[0]) // 2, (cols - keep[1]) // 2
    small = np.fft.ifft2(np.fft.ifftshift(spectrum[r0 : r0 + keep[0], c0 : c0 + keep[1]]))
    small *= keep[0] * keep[1] / (rows * cols)  # the same amplitudes on fewer samples
    return small.astype(np.complex64), pitch * cols / keep[1]


def depth_of_focus(wavelength: float, band: float) -> float:
    """The range over which an image of a wave's band stays in focus, λ/NA².

    Parameters
    ----------
    wavelength : float
        Wavelength λ [m].
    band : float
        The wave's highest spatial frequency [1/m]; the numerical aperture is
        NA = sin θ = λ·band, below 1.

    Returns
    -------
    float
        The depth of focus λ/NA² [m].

    Raises
    ------
    InputError
        Where ``band`` is not > 0 or λ·band >= 1, or ``wavelength`` is out of range.

    Examples
    --------
    >>> from holo_core.acquired import depth_of_focus
    >>> round(depth_of_focus(633e-9, 1e5) * 1e6, 1)   # NA 0.0633: µm
    158.0
    """
    na = validate.positive("band", band, "1/m") * validate.wavelength("wavelength", wavelength)
    if na >= 1:
        raise InputError(f"band must be below 1/λ = {1 / wavelength:.6g} 1/m; got {shown(band)}")
    return wavelength / na**2


__all__ = ["METRICS", "Focus", "autofocus", "decimate", "depth_of_focus", "focus_metric", "refocus"]
