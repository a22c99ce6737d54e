"""Fields and batches through the plane functions.

Each public propagation (``angular_spectrum``, ``fresnel``, ``fraunhofer``,
``rayleigh_sommerfeld``, ``tilt``, ``propagate_to_plane``, ``resample``) is a plane function
(one (H, W) field, scalar settings) wrapped by :func:`batched`, which adds:

- a :class:`~holo_core.scene.field.Field` in, a Field out: the wavelength and pitch come with
  it (passing them too is an error), and the result carries its new pitch and pose;
- batches: samples (..., H, W), and ``wavelength`` and ``distance`` as arrays, broadcast
  together as NumPy broadcasts (a field and 100 distances give 100 planes; a stack of 3
  colours with 3 wavelengths gives 3), in one call;
- the memory of the whole result checked before the first plane is computed, on the host or
  on the device, wherever the samples are; device samples stay on the device.

A single (H, W) array with scalar settings goes straight to the plane function, unchanged.
"""

from __future__ import annotations

import functools
import inspect
import math

import numpy as np

from .. import memory, validate
from ..opencl import get_runtime, is_device_array
from ..opencl.arrays import empty, put_plane
from ..scene.field import Field
from ..validate import InputError
from . import grid

VARYING = ("wavelength", "distance")  # settings that may be arrays over the batch


def batched(plane, *, moves=None, grid_of=None, returns_pitch=False):
    """A plane function that takes Fields and batches too (this module's docstring).

    Parameters
    ----------
    plane : callable
        ``plane(field, *, [wavelength,] pitch, ...)``: one (H, W) field and scalar settings
        (SI units) to one output plane.
    moves : callable, optional
        ``moves(settings)`` → (4, 4) array: where the output plane lies in the input plane's
        frame [m] (a Field's pose follows it); default the identity.
    grid_of : callable, optional
        ``grid_of(settings, shape, pitch)`` → (out shape, out pitch (x, y) [m]); default the
        input's grid.
    returns_pitch : bool
        The plane function returns (field, (x pitch, y pitch) [m]) (the far field's).

    Returns
    -------
    callable
        ``call(field, **settings)``: a single (H, W) array with scalar settings goes straight
        to ``plane``; a :class:`~holo_core.Field` gives a Field (its wavelength and pitch
        taken from it), a batch (..., H, W) and array-valued ``wavelength`` or ``distance``
        are broadcast together, the whole result's memory checked first.

    Raises
    ------
    InputError
        (from the call) Where a keyword is unknown, a Field comes with its own wavelength or
        pitch, or the batch shapes do not broadcast.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core.propagation import batched
    >>> def doubled(field, *, pitch):
    ...     return 2 * np.asarray(field)
    >>> batched(doubled)(np.ones((3, 4, 4)), pitch=1e-6).shape
    (3, 4, 4)
    """

    # the keywords it takes, checked before any work; a plane that passes **settings on (an
    # adjoint) leaves them to the function it calls
    forwards = bool(plane.__code__.co_flags & inspect.CO_VARKEYWORDS)
    taken = [p for p in _parameters(plane) if p != "field"]

    @functools.wraps(plane)
    def call(field, **settings):
        if not forwards:
            validate.keywords(plane.__name__, settings, taken)
        is_field = isinstance(field, Field)
        if not is_field and not _batched(field, settings):
            return plane(field, **settings)
        lam = None
        if is_field:
            for name in ("wavelength", "pitch"):
                if settings.get(name) is not None:
                    raise InputError(
                        f"{name} comes with the Field; leave it out (got {settings[name]!r})"
                    )
            samples, pose, lam = field.samples, field.pose, field.wavelength
            settings = {**settings, "pitch": field.pitch}
            if "wavelength" in _parameters(plane):
                settings["wavelength"] = lam
        else:
            samples, pose = field, np.eye(4)
            if not is_device_array(samples):
                samples = np.asarray(samples)
        run = _Run(plane, samples, pose, settings, moves, grid_of, returns_pitch)
        out, pitch, poses, far = run()
        if not is_field:
            return (out, far) if returns_pitch else out
        lam = np.broadcast_to(np.asarray(lam, np.float64), run.batch)
        return Field(samples=out, wavelength=lam, pitch=pitch, pose=poses)

    return call


def _parameters(plane) -> tuple:
    code = plane.__code__
    return code.co_varnames[: code.co_argcount + code.co_kwonlyargcount]


def _batched(field, settings) -> bool:
    ndim = field.ndim if is_device_array(field) else np.ndim(field)
    return ndim > 2 or any(np.ndim(settings.get(k)) > 0 for k in VARYING)


class _Run:
    """One batched call: the broadcast batch, its memory checked, then plane by plane."""

    def __init__(self, plane, samples, pose, settings, moves, grid_of, returns_pitch):
        if samples.ndim < 2 or 0 in samples.shape[-2:]:  # a batch of wavelengths over an
            # empty field would fail reshaping it, with no word of the field (tools/fuzz.py)
            raise InputError(
                f"field must be (..., H, W) with H, W >= 1; got shape {tuple(samples.shape)}"
            )
        self.plane, self.samples, self.settings = plane, samples, settings
        self.moves, self.returns_pitch = moves, returns_pitch
        self.batch_in = tuple(samples.shape[:-2])
        self.varying = {k: _numbers(k, settings[k]) for k in VARYING if settings.get(k) is not None}
        shapes = {
            "field": self.batch_in,
            **{k: v.shape for k, v in self.varying.items()},
            "pose": tuple(np.shape(pose)[:-2]),
        }
        try:
            self.batch = np.broadcast_shapes(*shapes.values())
        except ValueError:
            raise InputError(f"the batch shapes do not broadcast together: {shapes}") from None
        if 0 in self.batch:
            raise InputError(f"the batch must hold at least one plane; its shape is {self.batch}")
        self.pose = pose
        h, w = self.shape = tuple(samples.shape[-2:])
        self.pitch = grid.pitch_pair(settings["pitch"])
        first = {**settings, **{k: float(v.reshape(-1)[0]) for k, v in self.varying.items()}}
        self.out_shape, self.out_pitch = (
            grid_of(first, (h, w), self.pitch) if grid_of else ((h, w), self.pitch)
        )
        if (
            returns_pitch
            and len(self.varying)
            and np.ptp(np.prod(np.broadcast_arrays(*self.varying.values()), axis=0)) > 0
        ):
            raise InputError(
                "the far field's pitch λ·z/(N·pitch) must be one for the whole "
                "batch; give its entries one product wavelength·distance"
            )

    def __call__(self):
        batch, (h, w), (oh, ow) = self.batch, self.shape, self.out_shape
        count = math.prod(batch)
        on_device = is_device_array(self.samples)
        nbytes = 8.0 * count * oh * ow
        what = f"{count} planes of {oh}x{ow}"
        if on_device:
            rt = get_runtime()
            plane_bytes = 8.0 * max(h * w, oh * ow)
            memory.check_device(rt, what, nbytes + 8 * plane_bytes, max(nbytes, 4 * plane_bytes))
            out = empty(rt, (*batch, oh, ow))
        else:
            memory.check_host(what, 2 * nbytes)
            out = np.empty((*batch, oh, ow), np.complex64)
        source = np.broadcast_to(
            np.arange(max(1, math.prod(self.batch_in))).reshape(self.batch_in), batch
        )
        values = {k: np.broadcast_to(v, batch) for k, v in self.varying.items()}
        flat = self.samples.reshape(-1, h, w)
        poses = np.broadcast_to(self.pose, (*batch, 4, 4)).copy()
        pitch, far = self.out_pitch, None
        for i, idx in enumerate(np.ndindex(*batch)):
            kw = {
                **self.settings,
                **{k: float(v[idx]) for k, v in values.items()},
                "pitch": _scalar(self.pitch),
            }
            src = flat[int(source[idx])]
            if on_device and src.offset:
                src = src.copy()  # a plane of a stack: the plane functions take whole arrays
            result = self.plane(src, **kw)
            if self.returns_pitch:
                result, far = result
                pitch = far
            if on_device:
                put_plane(rt, out, i, result)
            else:
                out[idx] = result
            if self.moves is not None:
                poses[idx] = poses[idx] @ self.moves(kw)
        return out, pitch, poses, far


def _numbers(name: str, value) -> np.ndarray:
    """A setting that may vary over the batch: a number or a non-empty array of numbers."""
    try:
        a = np.asarray(value, np.float64)
    except (TypeError, ValueError):
        a = np.zeros(0)
    if not a.size:
        raise InputError(
            f"{name} must be a number or a non-empty array of numbers [m]; got {value!r}"[:300]
        )
    return a


def _scalar(pitch):
    """A pitch pair as the plane functions take it: a number where both axes agree."""
    return pitch[0] if pitch[0] == pitch[1] else pitch


def translation(x=0.0, y=0.0, z=0.0) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = x, y, z
    return m


def rigid(rotation, position=(0.0, 0.0, 0.0)) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = validate.rotation("rotation", rotation)
    m[:3, 3] = position
    return m
