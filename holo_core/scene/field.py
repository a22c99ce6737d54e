"""A sampled complex field that carries its optics (as prysm's Wavefront and odak's fields do):
samples, wavelength, pitch and the pose of the plane they lie on.

The samples stay where they are: a NumPy array on the host or an OpenCL device array; nothing
here copies them to the host unless :meth:`Field.to_numpy` is asked. Leading axes before the
last two are a batch (several wavelengths, distances or frames): samples (..., H, W), with a
wavelength and a pose per batch entry where they differ. The propagations, the tilt, the
resampling and the lens take a Field and return one with its optics updated
(:mod:`holo_core.propagation`, :func:`holo_core.optics.lens.thin_lens`).

Pixel centres follow the library's convention: column j at x = (j − (W−1)/2)·pitch_x, row i at
y = (i − (H−1)/2)·pitch_y, in the plane's own frame; the pose maps that frame to the world.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .. import preview, validate
from ..validate import InputError, shown


@dataclass(frozen=True, slots=True, kw_only=True, eq=False)
class Field:
    """Complex samples with their wavelength(s), pitch and plane pose.

    Parameters
    ----------
    samples : (..., H, W) complex array, NumPy or OpenCL device array
        The field on the plane's pixel centres, [row, col] = [y, x]; leading axes a batch.
    wavelength : float or array
        λ [m]; an array broadcast against the batch shape gives each entry its own.
    pitch : float or (float, float)
        Sample spacing [m] along x (columns) and y (rows).
    pose : (4, 4) or (..., 4, 4) array
        Plane-to-world pose [m] (rotation and translation; the samples lie on its z = 0 plane),
        one per batch entry where they differ. Default: the identity, the plane z = 0.

    Raises
    ------
    InputError
        Where ``samples`` is not (..., H, W), or the wavelength, pitch or pose is out of range.

    Examples
    --------
    A propagation takes a Field and returns one on the target plane:

    >>> import numpy as np
    >>> from holo_core import Field, angular_spectrum
    >>> f = Field(samples=np.ones((64, 64), complex), wavelength=633e-9, pitch=4e-6)
    >>> g = angular_spectrum(f, distance=1e-3)
    >>> g.samples.shape, round(float(g.pose[2, 3]), 6)
    ((64, 64), 0.001)
    """

    samples: object
    wavelength: object
    pitch: object
    pose: np.ndarray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self):
        s = self.samples
        if not _on_device(s):
            s = np.asarray(s)
            if not np.issubdtype(s.dtype, np.number):
                raise InputError(f"samples must be numeric; got dtype {s.dtype}")
            object.__setattr__(self, "samples", s)
        if s.ndim < 2 or 0 in s.shape[-2:]:
            raise InputError(
                f"samples must be (..., H, W) with H, W >= 1; got shape {tuple(s.shape)}"
            )
        batch = tuple(s.shape[:-2])
        lam = (
            np.asarray(self.wavelength, np.float64)
            if not isinstance(self.wavelength, str)
            else None
        )
        if lam is None or not _broadcasts(lam.shape, batch):
            raise InputError(
                f"wavelength must be a number [m] or an array broadcast against "
                f"the batch shape {batch}; got {shown(self.wavelength)}"[:300]
            )
        for v in lam.reshape(-1):
            validate.wavelength("wavelength", v)
        object.__setattr__(self, "wavelength", float(lam) if lam.ndim == 0 else lam)
        object.__setattr__(self, "pitch", pitches(self.pitch))
        pose = np.asarray(self.pose, np.float64) if np.size(self.pose) else np.zeros(0)
        if pose.ndim < 2 or pose.shape[-2:] != (4, 4) or not _broadcasts(pose.shape[:-2], batch):
            raise InputError(
                f"pose must be a (4, 4) plane-to-world matrix or one per batch "
                f"entry (..., 4, 4); got shape {pose.shape}"
            )
        for m in pose.reshape(-1, 4, 4):
            validate.rigid_pose("pose", m)
        object.__setattr__(self, "pose", pose)

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of one plane."""
        return tuple(self.samples.shape[-2:])

    @property
    def batch_shape(self) -> tuple[int, ...]:
        return tuple(self.samples.shape[:-2])

    @property
    def on_device(self) -> bool:
        return _on_device(self.samples)

    @property
    def size(self) -> tuple[float, float]:
        """Physical (width, height) [m]."""
        return self.shape[1] * self.pitch[0], self.shape[0] * self.pitch[1]

    def coords(self) -> tuple[np.ndarray, np.ndarray]:
        """(x (W,), y (H,)) pixel-centre positions [m] in the plane's frame."""
        (h, w), (px, py) = self.shape, self.pitch
        return (np.arange(w) - (w - 1) / 2) * px, (np.arange(h) - (h - 1) / 2) * py

    def wavelengths(self) -> np.ndarray:
        """λ [m] of every batch entry, an array of the batch shape."""
        return np.broadcast_to(np.asarray(self.wavelength, np.float64), self.batch_shape)

    def poses(self) -> np.ndarray:
        """The pose of every batch entry, (*batch, 4, 4)."""
        return np.broadcast_to(self.pose, (*self.batch_shape, 4, 4))

    def to_numpy(self) -> Field:
        """The same field with its samples on the host (a copy from the device, if there)."""
        return replace(self, samples=self.samples.get()) if self.on_device else self

    def __len__(self) -> int:
        if not self.batch_shape:
            raise TypeError("a single plane has no length; its batch shape is ()")
        return self.batch_shape[0]

    def __getitem__(self, index) -> Field:
        """The batch entries ``index`` picks (an int or slices over the batch axes), each
        with its own wavelength and pose."""
        batch = self.batch_shape
        if not batch:
            raise InputError("a single plane has no batch to index")
        index = index if isinstance(index, tuple) else (index,)
        if len(index) > len(batch) or any(i is Ellipsis or i is None for i in index):
            raise InputError(f"index the batch axes {batch} with ints or slices; got {index!r}")
        ids = np.arange(int(np.prod(batch))).reshape(batch)[index]
        samples = self.samples[index]
        return Field(
            samples=samples,
            wavelength=self.wavelengths().reshape(-1)[ids],
            pitch=self.pitch,
            pose=self.poses().reshape(-1, 4, 4)[ids],
        )

    def __repr__(self) -> str:
        lam = np.unique(self.wavelengths()) if self.batch_shape else [self.wavelength]
        lam = preview.lengths(lam if len(lam) <= 4 else [min(lam), max(lam)])
        px, py = self.pitch
        pitch = preview.length(px) if px == py else f"{preview.length(px)} x {preview.length(py)}"
        batch = f"batch {'x'.join(map(str, self.batch_shape))} of " if self.batch_shape else ""
        h, w = self.shape
        return f"Field({batch}{h}x{w}, λ {lam}, pitch {pitch}, {preview.where(self.samples)})"

    def _repr_png_(self) -> bytes:
        """A notebook's picture: |U| of the first plane, normalised, at most 512 px a side
        (a copy from the device of that plane only)."""
        first = self.samples[(0,) * len(self.batch_shape)] if self.batch_shape else self.samples
        first = first.get() if _on_device(first) else first
        return preview.png(preview.normalised(preview.thumbnail(np.abs(first))))


def pitches(pitch) -> tuple[float, float]:
    """A pitch [m] as (x, y): a number for both, or a pair; each in the optical range."""
    if np.ndim(pitch) == 0:
        p = validate.pitch("pitch", pitch)
        return p, p
    if np.shape(pitch) != (2,):
        raise InputError(f"pitch must be a number or a pair (x, y) [m]; got {shown(pitch)}"[:300])
    return validate.pitch("pitch", pitch[0]), validate.pitch("pitch", pitch[1])


def _on_device(a) -> bool:
    return hasattr(a, "queue") and hasattr(a, "get")  # an OpenCL array (scene imports no opencl)


def _broadcasts(shape, batch) -> bool:
    try:
        return np.broadcast_shapes(tuple(shape), tuple(batch)) == tuple(batch)
    except ValueError:
        return False
