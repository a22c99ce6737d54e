"""From a scan to a view in one step: the file read, the carrier found, the object wave
filtered out and placed at its distance, and a camera that frames it.

- :func:`import_acquired`: the scan (:func:`holo_core.io.acquired.read_acquired`) with its
  carrier found in the spectrum unless an angle is given or stated, stored as the
  hologram's reference angle and azimuth (and logged); with a ``distance``, the order is the
  one that focuses behind the hologram, and the objects' plane is its bounds.
- :func:`object_hologram`: the complex hologram of the object wave (the sideband filter's),
  its band the aperture's, its objects on the plane ``distance`` behind it: what the plate
  viewer renders, its depth that plane's.
- :func:`~holo_core.acquired.framing.default_camera` (``framing.py``): a camera that frames
  it, focused on the objects' plane.

The order by focus: the two orders are a wave and its conjugate; the +1 order comes into focus
behind the hologram (a virtual image at −distance), the twin in front (+distance). The one
whose amplitude at −distance has the higher Tamura coefficient (√(std/mean) of the amplitude:
a sharp image of an object that shows in amplitude, dark around it) is taken; the two
coefficients are logged, and a margin under :data:`ORDER_MARGIN` is warned (a pure phase
object: name the sideband).
"""

from __future__ import annotations

import logging
import math
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from .. import validate
from ..io.acquired import read_acquired
from ..scene.hologram import Hologram
from ..validate import InputError
from .carrier import Carrier, InlineHologramError, intensity_of, locate
from .filters import ITERATIONS, Aperture, sideband
from .focus import decimate, focus_metric, refocus
from .framing import checked_distance, plane_bounds

log = logging.getLogger(__name__)

ORDER_MARGIN = 0.05  # the orders' Tamura coefficients closer than this (relative): warned


class OrderWarning(UserWarning):
    """The two orders of an off-axis hologram focus alike at the stated distance.

    Warned by :func:`~holo_core.acquired.import_acquired` and
    :func:`~holo_core.acquired.object_hologram` where the order that should come into focus
    behind the hologram does not focus measurably better than its twin (a phase object, or a
    wrong distance): the order taken may be the twin. A subclass of ``UserWarning``.

    See Also
    --------
    holo_core.find_carrier : the carrier by the spectrum's rule (``sideband``) instead.
    """


@validate.public
def import_acquired(
    source,
    *,
    pitch=None,
    wavelength=None,
    reference_angle=None,
    reference_azimuth=None,
    page=None,
    dataset=None,
    distance=None,
    sideband="auto",
    find_carrier=True,
):
    """Import an acquired intensity hologram and find its carrier.

    The carrier is found as :mod:`holo_core.acquired.carrier` describes.

    Parameters
    ----------
    source, pitch, wavelength, reference_angle, reference_azimuth, page, dataset
        As :func:`holo_core.io.acquired.read_acquired` (the file, or an array, and its optics
        [m, rad]). A reference angle given or stated by the file is used as it is.
    distance : float, optional
        How far behind the hologram its objects lie [m]: the objects' plane becomes the
        hologram's bounds, and ``sideband='auto'`` takes the order that focuses there.
    sideband : 'auto', 'lower' or 'upper'
        Which of the spectrum's pair is the carrier: 'auto' by focus with a distance (this
        module's docstring), else 'lower'; or named, as holospy's ``sb``.
    find_carrier : bool
        False keeps an unknown angle at 0 (the scan as it is read).

    Returns
    -------
    Hologram (with ``reference_angle`` and ``reference_azimuth`` of the carrier), or a list for
    ``page='all'``. An in-line hologram (no sideband) is returned with angle 0 and logged.

    Raises
    ------
    InputError
        Where the source cannot be read (:func:`~holo_core.io.acquired.read_acquired`) or an
        argument is out of range, naming it.

    Examples
    --------
    Fringes of 62.5 mm⁻¹ at 633 nm: the reference angle is arcsin(λ·f) = 0.0396 rad.

    >>> import numpy as np
    >>> from holo_core import import_acquired
    >>> x = (np.arange(64) - 31.5) * 2e-6
    >>> fringes = np.tile(2 + 2 * np.cos(2 * np.pi * 62500 * x), (64, 1))
    >>> h = import_acquired(fringes, pitch=2e-6, wavelength=633e-9)
    >>> round(h.reference_angle, 4), h.intensity.shape
    (0.0396, (1, 64, 64))
    """
    validate.choice("sideband", sideband, ("auto", "lower", "upper"))
    read = read_acquired(
        source,
        pitch=pitch,
        wavelength=wavelength,
        reference_angle=reference_angle,
        reference_azimuth=reference_azimuth,
        page=page,
        dataset=dataset,
    )
    holograms = read if isinstance(read, list) else [read]
    if distance is not None:
        distance = checked_distance(distance, holograms[0])
    out = []
    for h in holograms:
        if find_carrier and reference_angle is None and h.reference_angle == 0:
            h = _with_carrier(h, sideband, distance, source)
        if distance is not None:
            h = replace(h, bounds=plane_bounds(h, distance))
        out.append(h)
    return out if isinstance(read, list) else out[0]


def _with_carrier(h: Hologram, side: str, distance, source) -> Hologram:
    """``h`` with the carrier found in its spectrum as its reference angle and azimuth."""
    name = source if isinstance(source, (str, bytes)) or hasattr(source, "__fspath__") else "array"
    intensity, pitch, wavelength = intensity_of(h, 0, None)
    try:
        carrier = locate(
            intensity, pitch, sideband="lower" if side == "auto" else side, wavelength=wavelength
        )
    except InlineHologramError as e:
        log.warning("%s: %s", name, e)
        return h
    if side == "auto" and distance is not None:
        carrier = _order_by_focus(h, carrier, distance)
    angle = carrier.angle
    if angle is None:
        raise InputError(
            f"{name}: its carrier {carrier.frequency} 1/m is beyond 1/λ: the "
            f"wavelength {wavelength!r} m cannot be right"
        )
    log.info("%s: %s", name, carrier.describe())
    return replace(h, reference_angle=angle, reference_azimuth=carrier.azimuth)


def _order_by_focus(h: Hologram, carrier: Carrier, distance: float) -> Carrier:
    """The carrier of the order whose wave is sharper at −``distance`` (this module's rule),
    judged on the aperture's band alone (the wave resampled to its Nyquist rate)."""
    wave, pitch = _baseband(h, carrier)
    lam = h.wavelengths[0]
    behind = focus_metric(refocus(wave, wavelength=lam, pitch=pitch, distance=-distance), "tamura")
    front = focus_metric(
        refocus(wave, wavelength=lam, pitch=pitch, distance=distance), "tamura"
    )  # the twin's amplitude behind: conj(o) carried by −d
    if abs(behind - front) < ORDER_MARGIN * max(behind, front):
        warnings.warn(
            f"the two orders focus alike at {distance:g} m behind the hologram "
            f"(Tamura {behind:.4g} and {front:.4g}): a phase object, or another "
            f"distance; the order taken may be the twin: name the sideband",
            OrderWarning,
            stacklevel=4,
        )
    twin = front > behind
    log.info(
        "orders at -%g m: Tamura %.4g (%s) against %.4g (the other): the %s",
        distance,
        behind,
        carrier.sideband,
        front,
        "other" if twin else carrier.sideband,
    )
    if not twin:
        return replace(carrier, rule=carrier.rule + "; the order that focuses behind")
    return Carrier(
        fx=-carrier.fx,
        fy=-carrier.fy,
        wavelength=carrier.wavelength,
        rule=carrier.rule.replace(carrier.sideband, "the other")
        + "; the order that focuses behind",
        contrast=carrier.contrast,
        half="upper" if carrier.sideband == "lower" else "lower",
    )


def _baseband(h: Hologram, carrier: Carrier) -> tuple[np.ndarray, float]:
    """The plain sideband filter's wave (radius |f_R|/3) on the coarsest grid that holds its
    band (cheap refocusing for the order's choice)."""
    wave = sideband(h, carrier=carrier, iterations=0)
    return decimate(wave, pitch=h.pitch, band=carrier.norm / 3)


@validate.public
def object_hologram(
    hologram: Hologram,
    *,
    distance=None,
    aperture: Aperture | None = None,
    reference_hologram=None,
    subtract=(),
    iterations=ITERATIONS,
) -> Hologram:
    """Turn an acquired intensity hologram into the complex hologram of its object wave.

    Parameters
    ----------
    hologram : Hologram
        An intensity Hologram (:func:`import_acquired`'s) with its carrier stated.
    distance : float, optional
        How far behind the hologram its objects lie [m]; default its bounds, as
        :func:`import_acquired` set them.
    aperture : Aperture, optional
        The sideband filter (:func:`~holo_core.acquired.sideband`); its band is the result's.
    reference_hologram : Hologram or (H, W) array, optional
        A reference (vacuum) hologram the wave is divided by.
    subtract : sequence of (H, W) arrays or Holograms
        Intensities taken from the hologram before filtering.
    iterations : int
        Passes that take the zero order and the twin away (as for
        :func:`~holo_core.acquired.sideband`).

    Returns
    -------
    Hologram
        The complex hologram: its object wave (:func:`~holo_core.acquired.sideband` with the
        stated carrier), its band the aperture's, its objects on the plane ``distance`` behind
        it.

    Raises
    ------
    InputError
        Where ``hologram`` is not an intensity Hologram, or no ``distance`` is given and the
        hologram does not state one.

    Notes
    -----
    The object wave is the virtual image's order O·R̄ of Eq. 20, at baseband.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import import_acquired, object_hologram
    >>> x = (np.arange(64) - 31.5) * 2e-6
    >>> fringes = np.tile(2 + 2 * np.cos(2 * np.pi * 62500 * x), (64, 1))
    >>> h = object_hologram(import_acquired(fringes, pitch=2e-6, wavelength=633e-9),
    ...                     distance=2e-3)
    >>> h.object_wave.shape, round(float(abs(h.object_wave[0, 32, 32])), 3)
    ((1, 64, 64), 1.0)
    """
    if not isinstance(hologram, Hologram) or hologram.intensity is None:
        raise InputError(
            f"hologram must be an intensity Hologram (import_acquired's); got "
            f"{type(hologram).__name__}"
        )
    if distance is None:
        bounds = np.asarray(hologram.bounds)
        if bounds[0, 2] != bounds[1, 2] or bounds[0, 2] >= 0:
            raise InputError(
                "distance must be given [m] (how far behind the hologram its "
                "objects lie): the hologram does not state it"
            )
        distance = -float(bounds[0, 2])
    distance = checked_distance(distance, hologram)
    if not hologram.reference_angle:
        raise InlineHologramError(
            "hologram states no carrier (its reference angle is 0): "
            "import it with holo_core.import_acquired, which finds it, "
            "or give the reference's angle and azimuth"
        )
    aperture = aperture or Aperture()
    waves = [
        sideband(
            hologram,
            c,
            aperture=aperture,
            reference_hologram=reference_hologram,
            subtract=subtract,
            iterations=iterations,
        )
        for c in range(len(hologram.wavelengths))
    ]
    lam = hologram.wavelengths[0]
    s = math.sin(hologram.reference_angle) / lam
    radius = aperture.radius_per_m(s, lam, hologram.band)
    return Hologram(
        object_wave=np.stack(waves),
        encoding="complex",
        wavelengths=hologram.wavelengths,
        pitch=hologram.pitch,
        plate=hologram.plate,
        bounds=plane_bounds(hologram, distance),
        band=min(radius * lam, 0.999),
        channels=hologram.channels,
    )


@validate.public
def complex_scan(path, *, pitch, wavelength, distance) -> Hologram | None:
    """The complex hologram of an EXR holding an acquired object wave as channels ``re`` and
    ``im`` (a phase-shifting setup's result), its objects on the plane ``distance`` [m] behind
    it; None for any other file."""
    from ..io.image import read_exr

    if Path(path).suffix.lower() != ".exr":
        return None
    header, channels = read_exr(path, what="scan")
    if "holo" in header or not {"re", "im"} <= set(channels):
        return None
    wave = (channels["re"] + 1j * channels["im"]).astype(np.complex64)[None]
    h = Hologram(object_wave=wave, encoding="complex", wavelengths=(wavelength,), pitch=pitch)
    return replace(h, bounds=plane_bounds(h, checked_distance(distance, h)))
