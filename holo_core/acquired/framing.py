"""Where an acquired hologram's objects are, and a camera that frames them: pure arithmetic
(no OpenCL, no physics stage), so Blender's process may call it.

- :func:`plane_bounds`, :func:`stated_plane`: objects on one plane ``distance`` behind the
  hologram are stated as a flat box of the hologram's size there; the plate viewer takes that
  plane as the view's depth.
- :func:`default_camera`: a camera on the hologram's axis that frames it and is focused on the
  objects' plane, its pupil wide enough for the whole band.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validate
from ..scene.camera import Camera, look_at
from ..scene.hologram import Hologram
from ..validate import InputError

FAR = 1000  # a distance beyond this many hologram widths looks like millimetres
VIEW_DISTANCE = 2  # the default camera stands this many object distances in front
FRAME_MARGIN = 1.05  # its field of view takes in the plate and this much more
VIEW_PIXELS = (256, 2048)  # the default view's side: the band's Nyquist sampling, within these


def checked_distance(distance, h: Hologram) -> float:
    """The objects' distance [m] behind ``h``: > 0, and warned
    (:class:`~holo_core.validate.UnitWarning`) beyond :data:`FAR` widths of the hologram."""
    d = validate.positive(
        "distance", validate.within("distance", distance, validate.MAX_LENGTH), "m"
    )
    width = max(h.size)
    if d > FAR * width:
        validate.warn_millimetres(
            "distance",
            d,
            f"is {d / width:.3g} times the hologram's "
            f"{width * 1e3:.3g} mm width: its objects would be resolved "
            f"no finer than {h.wavelengths[0] * d / width * 1e3:.3g} mm",
        )
    return d


def plane_bounds(h: Hologram, distance: float) -> np.ndarray:
    """The bounds of objects on one plane behind a hologram, the hologram's size wide.

    A flat box: the one plane the view's depth lies on.

    Parameters
    ----------
    h : Hologram
        The hologram (its ``size`` [m] is read).
    distance : float
        How far behind it the plane lies [m], > 0.

    Returns
    -------
    (2, 3) float64 ndarray
        [[x0, y0, z], [x1, y1, z]] [m] in the plate's frame, z = −``distance``.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Hologram
    >>> from holo_core.acquired import plane_bounds
    >>> h = Hologram(intensity=np.ones((1, 256, 256), np.float32), wavelengths=(633e-9,),
    ...              pitch=2e-6)
    >>> plane_bounds(h, 0.01)
    array([[-0.000256, -0.000256, -0.01    ],
           [ 0.000256,  0.000256, -0.01    ]])
    """
    w, ht = h.size
    return np.array([[-w / 2, -ht / 2, -distance], [w / 2, ht / 2, -distance]])


def stated_plane(h: Hologram) -> float | None:
    """The one plane behind a hologram its objects lie on, where its bounds state one.

    Parameters
    ----------
    h : Hologram
        The hologram (its ``bounds`` [m] are read).

    Returns
    -------
    float or None
        z [m] (negative: behind the plate) where the bounds are a flat box there, wide in x
        and y (an acquired hologram's stated distance, :func:`plane_bounds`'s), else None.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Hologram
    >>> from holo_core.acquired import plane_bounds, stated_plane
    >>> h = Hologram(intensity=np.ones((1, 64, 64), np.float32), wavelengths=(633e-9,),
    ...              pitch=2e-6)
    >>> h = Hologram(intensity=h.intensity, wavelengths=(633e-9,), pitch=2e-6,
    ...              bounds=plane_bounds(h, 0.01))
    >>> stated_plane(h)
    -0.01
    """
    bounds = np.asarray(h.bounds)
    z = float(bounds[0, 2])
    wide = bool((bounds[1, :2] > bounds[0, :2]).all())
    return z if wide and z == bounds[1, 2] and z < 0 else None


@validate.public
def default_camera(hologram: Hologram, *, distance=None, resolution=None) -> Camera:
    """A camera that frames a hologram and is focused on its objects' plane.

    Parameters
    ----------
    hologram : Hologram
        The hologram to frame.
    distance : float, optional
        How far behind the plate the objects' plane lies [m], > 0 (default: the middle of
        the hologram's bounds in z). One beyond ``FAR`` (1000) plate widths warns
        (``UnitWarning``: millimetres given for metres?).
    resolution : (int, int), optional
        The image's (W, H) [px]; default the band's Nyquist sampling of the framed plane,
        within ``VIEW_PIXELS`` (256 to 2048 on its larger side).

    Returns
    -------
    Camera
        On the hologram's axis, ``VIEW_DISTANCE`` (2) times the distance in front, so the
        frustum through the plate's edges takes in an object plane only 10 % wider than the
        plate; its field of view the plate's width and ``FRAME_MARGIN`` (5 %); focused on the
        objects' plane, its pupil taking in the whole cone of the hologram's band (sin θ)
        from there, so that it resolves what the hologram recorded.

    Raises
    ------
    InputError
        Where ``hologram`` is not a Hologram, or no ``distance`` is given and its bounds put
        no objects behind it.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Hologram
    >>> from holo_core.acquired import default_camera
    >>> h = Hologram(intensity=np.ones((1, 256, 256), np.float32), wavelengths=(633e-9,),
    ...              pitch=2e-6)
    >>> cam = default_camera(h, distance=0.01)
    >>> cam.resolution, cam.focus_distance
    ((416, 416), 0.03)
    """
    if not isinstance(hologram, Hologram):
        raise InputError(f"hologram must be a Hologram; got {type(hologram).__name__}")
    bounds = np.asarray(hologram.bounds)
    if distance is None:
        if bounds[0, 2] >= 0:
            raise InputError(
                "distance must be given [m]: the hologram's bounds put no objects behind it"
            )
        distance = -float(bounds[:, 2].mean())
    distance = checked_distance(distance, hologram)
    width, height = hologram.size
    lam = max(hologram.wavelengths)
    band = hologram.band or min(1.0, lam / (2 * hologram.pitch))
    standoff = VIEW_DISTANCE * distance
    plane = (width, height)
    if resolution is None:
        side = 2 * band / lam * max(plane) * (1 + 1 / VIEW_DISTANCE) * FRAME_MARGIN
        n = int(min(max(math.ceil(side / 16) * 16, VIEW_PIXELS[0]), VIEW_PIXELS[1]))
        resolution = (
            (n, max(16, round(n * height / width / 2) * 2))
            if width >= height
            else (max(16, round(n * width / height / 2) * 2), n)
        )
    sensor = 36.0  # spans the image's larger side, the plate's larger side
    lens = sensor * standoff / (FRAME_MARGIN * max(plane))
    pupil = 2 * (standoff + distance) * math.tan(math.asin(min(band, 0.999)))
    plate = np.asarray(hologram.plate, np.float64)
    eye = (plate @ np.array([0.0, 0.0, standoff, 1.0]))[:3]
    centre = (plate @ np.array([0.0, 0.0, -distance, 1.0]))[:3]
    return Camera(
        matrix_world=look_at(eye, centre, up=plate[:3, 1]),
        lens=lens,
        sensor_width=sensor,
        resolution=tuple(resolution),
        fstop=lens * 1e-3 / pupil,
        focus_distance=standoff + distance,
    )
