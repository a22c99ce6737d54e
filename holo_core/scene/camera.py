"""Blender's camera model, and the pinhole mapping of directions to pixels (Sect. VII-A, Eq. 22).

The camera looks down its local −Z with +Y up (Blender). A camera-space point (x, y, z), z < 0,
has the view tangents t = (x/−z, y/−z); the light reaching the camera from it travels along
−(t_x, t_y, −1)/|…|, whose direction cosines are Eq. 22's α = −t_x/√(t²+1), β = −t_y/√(t²+1).
Pixels follow Blender's view plane (``BKE_camera_params_compute_viewplane``): sensor fit, shift
in units of the fitted dimension, pixel aspect. Image row 0 is the top; pixel (row i, col j)
has its centre at (j + 0.5, i + 0.5) pixels from the top-left corner.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .. import validate
from ..validate import InputError

SENSOR_FITS = ("AUTO", "HORIZONTAL", "VERTICAL")


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class Camera:
    """A Blender camera: its pose, lens, sensor and image.

    Parameters
    ----------
    matrix_world : (4, 4) array
        Camera-to-world pose [m] (looks down local −Z, +Y up); default the identity.
    lens : float
        Focal length [mm] (Blender's unit for it).
    sensor_width, sensor_height : float
        Sensor size [mm].
    sensor_fit : {'AUTO', 'HORIZONTAL', 'VERTICAL'}
        'AUTO': ``sensor_width`` spans the larger image side.
    shift_x, shift_y : float
        Lens shift, in units of the fitted image side.
    resolution : (int, int)
        (W, H) [px].
    pixel_aspect : (float, float)
        (x, y) Blender's pixel aspect ratio.
    focus_distance : float, optional
        The plane in focus [m] (a thin lens, Eq. 24); needs ``fstop``.
    fstop : float, optional
        f-number N; the aperture diameter is lens/N. None is a pinhole.

    Raises
    ------
    InputError
        Where a field is out of its range (a length not finite and > 0, an unknown
        ``sensor_fit``), naming it.

    Notes
    -----
    A pixel's direction through the pinhole is the paper's Eq. 22 (directional cosines from
    the image coordinates and the field of view).

    Examples
    --------
    >>> from holo_core import Camera, look_at
    >>> cam = Camera(matrix_world=look_at((0, -1, 0), (0, 0, 0)), resolution=(64, 48))
    >>> [round(a, 4) for a in cam.field_of_view()]
    [0.6911, 0.5274]
    """

    matrix_world: np.ndarray = field(default_factory=lambda: np.eye(4))
    lens: float = 50.0
    sensor_width: float = 36.0
    sensor_height: float = 24.0
    sensor_fit: str = "AUTO"
    shift_x: float = 0.0
    shift_y: float = 0.0
    resolution: tuple = (640, 480)
    pixel_aspect: tuple = (1.0, 1.0)
    focus_distance: float | None = None
    fstop: float | None = None

    def __post_init__(self):
        m = validate.array("matrix_world", self.matrix_world, "a finite 4x4 matrix")
        if m.shape != (4, 4) or not np.isfinite(m).all():
            raise InputError(f"matrix_world must be a finite 4x4 matrix; got shape {m.shape}")
        if np.linalg.cond(m[:3, :3]) > 1e12 or not np.array_equal(m[3], [0, 0, 0, 1]):
            raise InputError(
                "matrix_world must be an invertible pose (rotation, positive "
                "scale, translation; bottom row 0 0 0 1); its 3x3 part is singular "
                "or its bottom row is not 0 0 0 1"
            )
        object.__setattr__(self, "matrix_world", m)
        for name in ("lens", "sensor_width", "sensor_height"):
            validate.positive(name, getattr(self, name), "mm")
        if self.sensor_fit not in SENSOR_FITS:
            raise InputError(f"sensor_fit must be one of {SENSOR_FITS}; got {self.sensor_fit!r}")
        validate.finite("shift_x", self.shift_x)
        validate.finite("shift_y", self.shift_y)
        w, h = validate.shape2d("resolution", self.resolution)
        object.__setattr__(self, "resolution", (w, h))
        for a in validate.pair("pixel_aspect", self.pixel_aspect):
            validate.positive("pixel_aspect", a)
        if self.fstop is not None:
            validate.positive("fstop", self.fstop)
            validate.positive("focus_distance", self.focus_distance, "m")
        elif self.focus_distance is not None:
            raise InputError(
                "focus_distance needs an fstop (None is a pinhole, focused everywhere)"
            )

    # -- pose ---------------------------------------------------------------------------------
    @property
    def position(self) -> np.ndarray:
        """The aperture's centre in the world [m]."""
        return self.matrix_world[:3, 3].copy()

    @property
    def rotation(self) -> np.ndarray:
        """Camera axes (X right, Y up, Z back) in world coordinates as columns, scale removed."""
        m = self.matrix_world[:3, :3]
        return m / np.linalg.norm(m, axis=0)

    @property
    def aperture_diameter(self) -> float | None:
        """lens / N [m] (Cycles' aperture), None for a pinhole."""
        return None if self.fstop is None else self.lens * 1e-3 / self.fstop

    # -- view plane ---------------------------------------------------------------------------
    def _plane(self):
        """(pixels per unit tangent, x shift [px], y shift [px], ycor) as Blender computes them."""
        w, h = self.resolution
        ax, ay = self.pixel_aspect
        ycor = ay / ax
        fit = self.sensor_fit
        if fit == "AUTO":
            fit = "HORIZONTAL" if ax * w >= ay * h else "VERTICAL"
        sensor = self.sensor_height if self.sensor_fit == "VERTICAL" else self.sensor_width
        viewfac = w if fit == "HORIZONTAL" else ycor * h
        return self.lens / sensor * viewfac, self.shift_x * viewfac, self.shift_y * viewfac, ycor

    def supersampled(self, s: int) -> Camera:
        """This camera with s × s fine pixels in each of its pixels (the same field of view)."""
        if s == 1:
            return self
        w, h = self.resolution
        return replace(self, resolution=(w * s, h * s))

    def cropped(self, left: int, top: int, width: int, height: int) -> Camera:
        """The camera of a region of this one's image, ``width`` x ``height`` pixels from
        (``left``, ``top``) [px, from the top-left corner]: each pixel keeps its ray (a
        render cropped to its border)."""
        w, h = self.resolution
        if not (0 <= left < left + width <= w and 0 <= top < top + height <= h):
            raise InputError(
                f"crop ({left}, {top}, {width}, {height}) must lie inside the {w}x{h} image"
            )
        s, dx, dy, ycor = self._plane()
        dx += left + width / 2 - w / 2
        dy += ycor * (h / 2 - top - height / 2)
        return replace(
            self,
            resolution=(width, height),
            sensor_fit="HORIZONTAL",
            sensor_width=self.lens * width / s,
            shift_x=dx / width,
            shift_y=dy / width,
        )

    def pixel_tangents(self, rows=None, cols=None) -> tuple[np.ndarray, np.ndarray]:
        """View tangents (t_x, t_y) of the pixel centres, each (H, W); or of given continuous
        (rows, cols) positions measured from the top-left corner in pixels."""
        w, h = self.resolution
        if rows is None:
            rows, cols = np.meshgrid(np.arange(h) + 0.5, np.arange(w) + 0.5, indexing="ij")
        s, dx, dy, ycor = self._plane()
        tx = (np.asarray(cols) - w / 2 + dx) / s
        v = h - np.asarray(rows)  # from the bottom edge
        ty = (v * ycor - 0.5 * ycor * h + dy) / s
        return tx, ty

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """World points (N, 3) [m] → ((N, 2) pixel positions (col, row) from the top-left
        corner, (N,) planar depth along the view axis [m]); points behind give NaN."""
        p = np.atleast_2d(np.asarray(points, np.float64))
        local = (p - self.position) @ self.rotation
        depth = -local[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            tx, ty = local[:, 0] / depth, local[:, 1] / depth
        w, h = self.resolution
        s, dx, dy, ycor = self._plane()
        col = tx * s + w / 2 - dx
        row = h - (ty * s + 0.5 * ycor * h - dy) / ycor
        xy = np.stack([col, row], -1)
        xy[depth <= 0] = np.nan
        return xy, depth

    def direction_cosines(self, rows=None, cols=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Eq. 22: (α, β, γ) per pixel (H, W) of the light arriving along each pixel's ray,
        in camera axes; or at given (rows, cols) positions (:meth:`pixel_tangents`)."""
        tx, ty = self.pixel_tangents(rows=rows, cols=cols)
        n = np.sqrt(tx * tx + ty * ty + 1)
        return -tx / n, -ty / n, 1 / n

    def tangent_steps(self) -> tuple[float, float, float, float]:
        """(t_x of column 0, its step per column, t_y of row 0, its step per row): the pixel
        centres' view tangents (:meth:`pixel_tangents`) are affine in their column and row,
        so a kernel finds any pixel's ray from these four numbers."""
        w, h = self.resolution
        s, dx, dy, ycor = self._plane()
        return (
            (0.5 - w / 2 + dx) / s,
            1 / s,
            ((h - 0.5) * ycor - 0.5 * ycor * h + dy) / s,
            -ycor / s,
        )

    def direction_range(self) -> tuple[np.ndarray, np.ndarray]:
        """((α, β) least, (α, β) greatest) of :meth:`direction_cosines` over the pixels, from
        the image's edge pixels alone: α = −t_x/√(1 + t_x² + t_y²) is monotone in t_x along a
        row (β likewise along a column), so its extremes lie in the first or last column."""
        w, h = self.resolution
        rows, cols = np.arange(h) + 0.5, np.arange(w) + 0.5
        edge_rows = np.concatenate([rows, rows, np.full(2 * w, 0.5)])
        edge_rows[2 * h + w :] = h - 0.5
        edge_cols = np.concatenate([np.full(h, 0.5), np.full(h, w - 0.5), cols, cols])
        ab = np.stack(self.direction_cosines(rows=edge_rows, cols=edge_cols)[:2])
        return ab.min(1), ab.max(1)

    def pixel_angle(self) -> float:
        """The angle one pixel spans at the image centre [rad] (the smaller of x and y)."""
        s, _, _, ycor = self._plane()
        return min(1.0, ycor) / s

    def field_of_view(self) -> tuple[float, float]:
        """Full (horizontal, vertical) angles of view through the image centre [rad]."""
        w, h = self.resolution
        s, _, _, ycor = self._plane()
        return 2 * math.atan(w / (2 * s)), 2 * math.atan(ycor * h / (2 * s))


def look_at(eye, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Build a camera-to-world matrix at ``eye`` looking at ``target``, ``up`` kept up.

    Parameters
    ----------
    eye : (3,) array_like
        The camera's position [m].
    target : (3,) array_like
        The point it looks at [m].
    up : (3,) array_like
        The world direction kept up in the image (any non-zero length).

    Returns
    -------
    (4, 4) ndarray
        Camera-to-world pose [m]: the camera looks down its local −Z, +Y up.

    Raises
    ------
    InputError
        Where ``up`` is zero or ``target`` equals ``eye``.

    Examples
    --------
    >>> from holo_core import look_at
    >>> m = look_at((0, -1, 0), (0, 0, 0))
    >>> m[:3, 3].tolist(), m[:3, 2].round(3).tolist()
    ([0.0, -1.0, 0.0], [0.0, -1.0, 0.0])
    """
    eye, target = validate.vector("eye", eye, 3, "m"), validate.vector("target", target, 3, "m")
    up = validate.vector("up", up, 3)
    if not np.linalg.norm(up) > 0:
        raise InputError(f"up must be a non-zero direction; got {up.tolist()}")
    back = eye - target
    if not np.linalg.norm(back) > 0:
        raise InputError(f"look_at needs target != eye; both are {eye.tolist()} m")
    z = back / np.linalg.norm(back)
    x = np.cross(up, z)
    if np.linalg.norm(x) < 1e-12:
        x = np.cross((0.0, 1.0, 0.0) if abs(z[1]) < 0.9 else (1.0, 0.0, 0.0), z)
    x /= np.linalg.norm(x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, np.cross(z, x), z, eye
    return m
