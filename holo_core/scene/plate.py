"""The holographic plate: its pose and size in the world, and the viewing zone it is recorded
for. The hologram is its z = 0 plane, viewers at z > 0.

A plate is a scene asset, independent of any camera: what it records depends on the scene, its
placement, size and sampling, its wavelengths, and its viewing zone, the region from which it
will be looked at (:class:`ViewingZone`, a box in the plate's frame). A camera whose pupil lies
inside the zone sees the plate sharp and complete; moving, aiming or refocusing it there never
calls for a new recording.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from .. import validate
from ..validate import InputError, shown

log = logging.getLogger(__name__)
DEFAULT_ZONE_MARGIN = 0.05  # [m] the default zone reaches this far beyond the camera's pupil
# [m] a zone fitted to a shot's cameras (a plate set's parts, Fit Zone to Shot or to Camera)
# reaches this far beyond their pupils: their own positions need no margin, and the recording
# grows along each axis as the square of the zone's width there (pupil + 2 margins), so at a
# 14 mm pupil 5 mm costs 2.9 times no margin, 1 cm 5.8 times, 5 cm 64 times (a 1 m dolly's
# set at 1280x720: 13.5 GiB, 21 GiB, 137 GiB)
SHOT_ZONE_MARGIN = 0.005


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class ViewingZone:
    """The region a plate is looked at from: an axis-aligned box in the plate's frame.

    Parameters
    ----------
    centre : (3,) tuple of float
        The box's centre [m] in the plate's frame (z > 0: in front of the plate).
    half_extents : (3,) tuple of float
        Its half widths [m] along the plate's x, y and z axes, each >= 0.
    pupil : float
        The entrance pupil [m] the zone is made for (the camera's aperture diameter; it sets
        how far apart the plate's emitters may lie, one resolved spot seen from there); 0 when
        unknown.
    pixel : float
        The pixel angle [rad] of the views the zone is made for (with the pupil, it sets the
        wavelength: views resolve a fine pixel); 0 when unknown.

    Raises
    ------
    InputError
        Where a field is not finite or out of its range (a negative half extent), naming it.

    Examples
    --------
    >>> from holo_core import ViewingZone
    >>> ViewingZone(centre=(0, 0, 0.5), half_extents=(0.1, 0.1, 0.1))
    ViewingZone(centre=(0.0, 0.0, 0.5), half_extents=(0.1, 0.1, 0.1), pupil=0.0, pixel=0.0)
    """

    centre: tuple
    half_extents: tuple
    pupil: float = 0.0
    pixel: float = 0.0

    def __post_init__(self):
        c = validate.vector("zone centre", self.centre, 3, "m")
        e = validate.vector("zone half_extents", self.half_extents, 3, "m")
        if (np.abs(c) > validate.MAX_LENGTH).any() or (e > validate.MAX_LENGTH).any():
            raise InputError(
                f"the viewing zone must lie within {validate.MAX_LENGTH:g} m; got "
                f"centre {c.tolist()}, half_extents {e.tolist()}"
            )
        if (e < 0).any():
            raise InputError(f"zone half_extents must be >= 0 [m]; got {e.tolist()}")
        if c[2] - e[2] <= 0:
            raise InputError(
                f"the viewing zone must lie in front of the plate (z > 0 in its "
                f"frame); it reaches z = {c[2] - e[2]:.4g} m"
            )
        pupil = validate.finite("zone pupil", self.pupil, "m")
        if not 0 <= pupil <= validate.MAX_LENGTH:
            raise InputError(
                f"zone pupil must be in [0, {validate.MAX_LENGTH:g}] [m]; got {self.pupil!r}"
            )
        object.__setattr__(self, "centre", tuple(map(float, c)))
        object.__setattr__(self, "half_extents", tuple(map(float, e)))
        object.__setattr__(self, "pupil", pupil)
        pixel = validate.finite("zone pixel", self.pixel, "rad")
        if not 0 <= pixel <= math.pi:
            raise InputError(f"zone pixel must be in [0, π] [rad]; got {shown(self.pixel)}")
        object.__setattr__(self, "pixel", pixel)

    @classmethod
    def around(
        cls, position, pupil: float = 0.0, margin: float = DEFAULT_ZONE_MARGIN, pixel: float = 0.0
    ):
        """The zone covering a pupil of diameter ``pupil`` [m] centred at ``position`` (3,) [m]
        (the plate's frame), ``margin`` [m] beyond it in every direction (in depth too), for
        views of pixels ``pixel`` [rad]."""
        margin = validate.finite("zone margin", margin, "m")
        if margin < 0:
            raise InputError(f"zone margin must be >= 0 [m]; got {shown(margin)}")
        pupil = validate.finite("pupil", pupil, "m")
        p = validate.vector("position", position, 3, "m")
        if p[2] <= 0:  # a zone behind the plate sees none of its light
            raise InputError(
                f"position must be in front of the plate (z > 0 in its frame); "
                f"got ({p[0]:g}, {p[1]:g}, {p[2]:g}) m"
            )
        half = pupil / 2 + margin
        depth = min(margin, 0.5 * float(p[2]))  # never reaching the plate
        return cls(centre=tuple(p), half_extents=(half, half, depth), pupil=pupil, pixel=pixel)

    @classmethod
    def fit(
        cls, positions, pupil: float = 0.0, margin: float = DEFAULT_ZONE_MARGIN, pixel: float = 0.0
    ):
        """The smallest zone holding a pupil of diameter ``pupil`` [m] at every one of
        ``positions`` (N, 3) [m] (a shot's camera path, the plate's frame), ``margin`` [m]
        beyond it (in depth, at most half the nearest position's distance), for views of
        pixels ``pixel`` [rad]."""
        p = np.atleast_2d(validate.array("positions", positions, "(N, 3) positions [m]"))
        if p.ndim != 2 or p.shape[1] != 3 or not len(p) or not np.isfinite(p).all():
            raise InputError(
                f"positions must be (N, 3) finite camera positions [m]; got shape {p.shape}"
            )
        margin = validate.finite("zone margin", margin, "m")
        if margin < 0:
            raise InputError(f"zone margin must be >= 0 [m]; got {shown(margin)}")
        pupil = validate.finite("pupil", pupil, "m")
        lo, hi = p.min(0), p.max(0)
        reach = pupil / 2 + margin
        depth = (hi[2] - lo[2]) / 2 + min(margin, 0.5 * float(lo[2]))
        return cls(
            centre=tuple((lo + hi) / 2),
            half_extents=((hi[0] - lo[0]) / 2 + reach, (hi[1] - lo[1]) / 2 + reach, depth),
            pupil=pupil,
            pixel=pixel,
        )

    def corners(self) -> np.ndarray:
        """The box's eight corners (8, 3) [m] in the plate's frame."""
        c, half = np.asarray(self.centre, np.float64), np.asarray(self.half_extents)
        return box_corners((c - half, c + half))

    def distance_outside(self, point, radius: float = 0.0) -> float:
        """How far [m] a ball of ``radius`` [m] at ``point`` (3,) [m] (the plate's frame)
        reaches beyond the zone: 0 when it lies inside."""
        d = np.abs(np.asarray(point, np.float64) - self.centre) - self.half_extents
        lateral = np.maximum(d[:2] + radius, 0)
        return float(math.hypot(*lateral) + max(d[2], 0.0))

    def describe(self) -> str:
        (x, y, z), (hx, hy, hz) = self.centre, self.half_extents
        return (
            f"the box centred at ({x:.4g}, {y:.4g}, {z:.4g}) m in the plate's frame, "
            f"±({hx:.4g}, {hy:.4g}, {hz:.4g}) m"
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class Carrier:
    """The converging spherical carrier of a plate's samples.

    centre : (3,) [m] the point it converges on (the zone's centre), the plate's frame, z > 0
    origin : (x, y) [m] of sample (row 0, column 0) in the plate's frame: the samples cover
        the window the zone's light crosses, not necessarily the plate's centre
    row_pitch : [m] the rows' spacing along y (the columns': the hologram's pitch); a zone
        wider than tall asks fewer rows
    """

    centre: tuple
    origin: tuple
    row_pitch: float

    def __post_init__(self):
        c = validate.vector("carrier centre", self.centre, 3, "m")
        if not c[2] > 0:
            raise InputError(
                f"carrier centre must lie in front of the plate (z > 0 in its "
                f"frame) [m]; got {c.tolist()}"
            )
        o = validate.vector("carrier origin", self.origin, 2, "m")
        object.__setattr__(self, "centre", tuple(map(float, c)))
        object.__setattr__(self, "origin", tuple(map(float, o)))
        object.__setattr__(self, "row_pitch", validate.pitch("carrier row_pitch", self.row_pitch))

    def coords(self, pitch: float, rows, cols) -> tuple[np.ndarray, np.ndarray]:
        """(x (cols,), y (rows,)) [m] of the samples ``rows`` and ``cols`` (index ranges or
        arrays) in the plate's frame, columns ``pitch`` [m] apart."""
        return (
            self.origin[0] + np.asarray(cols, np.float64) * pitch,
            self.origin[1] + np.asarray(rows, np.float64) * self.row_pitch,
        )

    def phase(self, wavelength: float, pitch: float, rows, cols) -> np.ndarray:
        """k·|x − c| reduced to [0, 2π) (rows, cols) float64 at the samples."""
        x, y = self.coords(pitch, rows, cols)
        cx, cy, cz = self.centre
        r = np.sqrt((x[None, :] - cx) ** 2 + (y[:, None] - cy) ** 2 + cz * cz)
        return np.remainder(2 * math.pi / wavelength * r, 2 * math.pi)


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class Plate:
    """The holographic plate in the world.

    Parameters
    ----------
    matrix_world : (4, 4) array
        Plate-to-world pose [m] (rotation and translation; the hologram is its z = 0 plane,
        viewers at z > 0).
    width, height : float
        The plate's physical size [m], > 0.
    zone : ViewingZone, optional
        The zone it is recorded for, or None: chosen when recording, from a camera if one is
        given.

    Raises
    ------
    InputError
        Where the pose is not a rigid (4, 4) transform or a size is not finite and > 0.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Plate
    >>> plate = Plate(matrix_world=np.eye(4), width=0.01, height=0.01)
    >>> plate.width, plate.zone
    (0.01, None)
    """

    matrix_world: np.ndarray
    width: float
    height: float
    zone: ViewingZone | None = None

    def __post_init__(self):
        m = validate.rigid_pose("plate matrix_world", self.matrix_world)
        object.__setattr__(self, "matrix_world", m)
        validate.positive("plate width", self.width, "m")
        validate.positive("plate height", self.height, "m")
        if self.zone is not None and not isinstance(self.zone, ViewingZone):
            raise InputError(f"zone must be a ViewingZone or None; got {type(self.zone).__name__}")

    def to_plate(self, points) -> np.ndarray:
        """World points (N, 3) [m] in the plate's frame."""
        m = self.matrix_world
        return (np.asarray(points, np.float64) - m[:3, 3]) @ m[:3, :3]

    def zone_for(self, camera, margin: float = DEFAULT_ZONE_MARGIN) -> ViewingZone:
        """The zone covering ``camera``'s pupil (its aperture, lens/f-stop; a pinhole's is
        taken as a point) with ``margin`` [m] around it."""
        position = self.to_plate(camera.position[None])[0]
        if position[2] <= 0:
            raise InputError(
                f"the camera must be in front of the plate (z > 0 in its frame) to "
                f"define its viewing zone; it is at z = {position[2]:.4g} m"
            )
        return ViewingZone.around(
            position, camera.aperture_diameter or 0.0, margin, camera.pixel_angle()
        )

    def recording_zone(self, zone, camera, margin, bounds) -> ViewingZone:
        """The viewing zone of a recording: ``zone``, else the plate's own, else one around
        ``camera``'s pupil (``margin`` [m]), else the plate's extent mirrored at the objects'
        distance in front of it (``bounds`` (2, 3) [m], the plate's frame)."""
        if zone is not None:
            if not isinstance(zone, ViewingZone):
                raise InputError(f"zone must be a ViewingZone or None; got {type(zone).__name__}")
            return zone
        if self.zone is not None:
            return self.zone
        if camera is not None:
            return self.zone_for(camera, margin)
        distance = -float(bounds[1, 2])
        zone = ViewingZone(
            centre=(0.0, 0.0, distance),
            half_extents=(self.width / 2, self.height / 2, distance / 4),
        )
        log.info("plate: no camera and no viewing zone given: %s", zone.describe())
        return zone


def box_corners(bounds) -> np.ndarray:
    """The eight corners (8, 3) [m] of the box ``bounds`` (min, max corners (2, 3) [m])."""
    lo, hi = np.asarray(bounds, np.float64)
    return np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
