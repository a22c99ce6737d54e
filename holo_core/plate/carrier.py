"""The carrier a plate's samples are stored against: the spherical wave converging on the
centre of its viewing zone, and the physical field re-modulated from them.

The light that reaches a zone of width w at distance L from one plate point leaves it within
about w/L of the direction towards the zone; only that direction changes across the plate.
Stored as B(x) = O(x)·exp(+ik|x − c|), the object wave O times the conjugate of the wave
converging on the zone's centre c, the samples are baseband: their band is the zone's angle,
not the widest angle between the plate's normal and the objects, and their pitch λ/(2·band)
follows what the zone can see (facts §7). The physical field is O = B·exp(−ik|x − c|), exact
at every sample (:func:`modulate`); the phase is formed in float64 and reduced before the
product.

Wherever the physical field is needed on another grid (a display's or a print's pitch, a
propagation's), :func:`physical_field` interpolates B band-limited and re-modulates it: O's
local frequency is B's plus the carrier's, sin θ/λ of the line from x to c, so O needs a far
finer grid than B (:func:`physical_pitch`). The interpolation is a Kaiser-windowed sinc of
``TAPS`` samples a side, exact (to ``RIPPLE``) over the band of the zone itself, B's band
without its soft rim, |f| <= (1 − ``TRANSITION``)·f_N (f_N its Nyquist frequency), and it
rejects B's spectral images from (1 + ``TRANSITION``)·f_N on; the rim's light, between, is
kept in part. Only the samples within ``TAPS`` of the grid are read, so a region of a tiled
plate reads only its tiles.
"""

from __future__ import annotations

import math

import numpy as np

from .. import memory, validate
from ..scene.field import Field
from ..scene.hologram import Hologram
from ..scene.plate import Carrier
from ..validate import InputError
from .zone_light import RIM

TAPS = 32  # samples a side of the interpolation kernel
# half the kernel's transition band, a fraction of f_N: the zone's soft rim, the part of B's band
# the zone proper lacks
TRANSITION = RIM / (1 + RIM)
RIPPLE = 1e-6  # the kernel's pass-band ripple and stop-band leak (120 dB)
BLOCK = 512  # output samples a side computed at once
FIELD_BYTES = 24  # host bytes per output sample: the field, the block's parts


def modulate(
    samples, carrier: Carrier, *, wavelength: float, pitch: float, rows=None, cols=None
) -> np.ndarray:
    """The physical object wave O = B·exp(−ik|x − c|) (complex64) of ``samples`` B
    ((..., rows, cols), the window's ``rows`` and ``cols`` index ranges, default from 0)."""
    b = np.asarray(samples)
    h, w = b.shape[-2:]
    rows = np.arange(h) if rows is None else rows
    cols = np.arange(w) if cols is None else cols
    return (b * np.exp(-1j * carrier.phase(wavelength, pitch, rows, cols))).astype(np.complex64)


def demodulate(
    field, carrier: Carrier, *, wavelength: float, pitch: float, rows=None, cols=None
) -> np.ndarray:
    """The stored samples B = O·exp(+ik|x − c|) (complex64) of an object wave ``field`` O on
    the carrier's sample grid (the inverse of :func:`modulate`)."""
    o = np.asarray(field)
    h, w = o.shape[-2:]
    rows = np.arange(h) if rows is None else rows
    cols = np.arange(w) if cols is None else cols
    return (o * np.exp(1j * carrier.phase(wavelength, pitch, rows, cols))).astype(np.complex64)


def window(h: Hologram) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1) [m], the plate's frame: the centres of a carrier plate's first and
    last samples, the window its samples cover."""
    _carrier_plate(h)
    (x0, x1), (y0, y1) = h.carrier.coords(h.pitch, [0, h.shape[0] - 1], [0, h.shape[1] - 1])
    return float(x0), float(y0), float(x1), float(y1)


@validate.scale_free()
def physical_pitch(h: Hologram, channel=0, region=None) -> float:
    """The largest pitch [m] that samples the physical field of ``channel`` of the carrier
    plate ``h`` over ``region`` (x0, y0, x1, y1) [m] (default: its :func:`window`) without
    aliasing: O's frequency along each axis reaches |sin θ|/λ of the carrier (the direction
    from x to its centre, at its steepest over the region) plus B's Nyquist frequency."""
    _carrier_plate(h)
    channel = validate.index("channel", channel, len(h.wavelengths))
    x0, y0, x1, y1 = _region(h, region)
    cx, cy, cz = h.carrier.centre

    def steepest(lo, hi, c, other_lo, other_hi, other_c):
        """The largest |direction cosine| along one axis of the line from the region to the
        centre: the region's farthest point along the axis, its nearest across it."""
        along = max(abs(lo - c), abs(hi - c))
        across = max(other_lo - other_c, 0.0, other_c - other_hi)
        return along / math.sqrt(along * along + across * across + cz * cz)

    lam = h.wavelengths[channel]
    reach = 1 + TRANSITION  # the kernel passes B's images up to here, a little beyond f_N
    fx = steepest(x0, x1, cx, y0, y1, cy) / lam + reach / (2 * h.pitch)
    fy = steepest(y0, y1, cy, x0, x1, cx) / lam + reach / (2 * h.row_pitch)
    return 1 / (2 * max(fx, fy))


@validate.scale_free()
def physical_field(h: Hologram, channel=0, *, pitch=None, region=None) -> Field:
    """Return the physical object wave of one channel of a complex plate, as a Field.

    Parameters
    ----------
    h : Hologram
        A complex plate.
    channel : int
        Index into its channels.
    pitch : float, optional
        The output grid's pitch [m]; default :func:`physical_pitch`, the largest that holds O
        over the region.
    region : (x0, y0, x1, y1), optional
        The window [m] in the plate's frame the grid is centred on; default the carrier's
        :func:`window`.

    Returns
    -------
    Field
        Complex64 samples of O, its wavelength, ``pitch`` and the pose of its grid's centre.

    Raises
    ------
    InputError
        Where ``h`` is not a complex plate, or ``channel``, ``pitch`` or ``region`` is out of
        range.

    Notes
    -----
    A carrier plate's samples B are interpolated band-limited onto the grid and re-modulated:
    O = B·exp(−ik``|x − c|``), the phase in float64 (module docstring). Beyond the window O is
    zero: no light the zone sees crosses the plate there. Only the samples the grid needs are
    read (a tiled plate's tiles). A plate without a carrier holds O: its samples cut to the
    region, at its own pitch.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Camera, Mesh, Plate, look_at, record_hologram
    >>> camera = Camera(matrix_world=look_at((0, 0, 0.3), (0, 0, -0.01), up=(0, 1, 0)),
    ...                 resolution=(32, 24), fstop=8.0, focus_distance=0.31)
    >>> triangle = Mesh(vertices=np.array([[-0.01, -0.01, -0.01], [0.01, -0.01, -0.01],
    ...                                    [0.0, 0.01, -0.01]]),
    ...                 triangles=np.array([[0, 1, 2]]), colours=np.ones((3, 3)))
    >>> plate = Plate(matrix_world=np.eye(4), width=0.03, height=0.03)
    >>> h = record_hologram([triangle], plate=plate, camera=camera)
    >>> from holo_core import physical_field
    >>> f = physical_field(h)
    >>> f.samples.ndim, f.pitch[0] < h.pitch
    (2, True)
    """
    if not isinstance(h, Hologram):
        raise InputError(f"hologram must be a Hologram; got {type(h).__name__}")
    channel = validate.index("channel", channel, len(h.wavelengths))
    if h.encoding != "complex":
        raise InputError(
            "an intensity hologram holds |O + R|², not the object wave: "
            "holo_core.plate.reconstruct or sideband gives its object wave"
        )
    lam = h.wavelengths[channel]
    if h.carrier is None:
        return _full_band(h, channel, pitch, region)
    x0, y0, x1, y1 = _region(h, region)
    pitch = physical_pitch(h, channel, region) if pitch is None else validate.pitch("pitch", pitch)
    xs, ys = _grid(x0, x1, pitch), _grid(y0, y1, pitch)
    memory.check_host(
        f"the physical field's {len(xs)}x{len(ys)} samples at {pitch:.3g} m "
        f"(ask a region or a coarser pitch)",
        FIELD_BYTES * len(xs) * len(ys),
    )
    samples = field_at(h, channel, xs, ys)
    pose = np.asarray(h.plate, np.float64) @ _translation((x0 + x1) / 2, (y0 + y1) / 2)
    return Field(samples=samples, wavelength=lam, pitch=pitch, pose=pose)


def field_at(h: Hologram, channel: int, xs, ys) -> np.ndarray:
    """O (len(ys), len(xs)) complex64 of ``channel`` of the carrier plate ``h`` at the grid of
    columns ``xs`` and rows ``ys`` [m] (each increasing, the plate's frame): B interpolated
    band-limited (module docstring) and re-modulated by the carrier, BLOCK rows at a time
    (each band of B's rows read once)."""
    xs, ys = np.asarray(xs, np.float64), np.asarray(ys, np.float64)
    c = h.carrier
    k = 2 * math.pi / h.wavelengths[channel]
    out = np.zeros((len(ys), len(xs)), np.complex64)
    columns = [
        (b, *kernel((xs[b : b + BLOCK] - c.origin[0]) / h.pitch, h.shape[1]))
        for b in range(0, len(xs), BLOCK)
    ]
    columns = [(b, c0, c1, kx) for b, c0, c1, kx in columns if c1 > c0]
    if not columns:
        return out
    first, last = min(c0 for _, c0, _, _ in columns), max(c1 for _, _, c1, _ in columns)
    dx2 = (xs - c.centre[0]) ** 2
    for a in range(0, len(ys), BLOCK):
        y = ys[a : a + BLOCK]
        r0, r1, ky = kernel((y - c.origin[1]) / c.row_pitch, h.shape[0])
        if r1 <= r0:
            continue
        rows = ky @ np.asarray(h.object_wave[channel, r0:r1, first:last], np.complex64)
        dyz2 = (y - c.centre[1]) ** 2 + c.centre[2] ** 2
        for b, c0, c1, kx in columns:
            n = kx.shape[0]
            r = np.sqrt(dx2[None, b : b + n] + dyz2[:, None])
            out[a : a + len(y), b : b + n] = (rows[:, c0 - first : c1 - first] @ kx.T) * np.exp(
                -1j * np.remainder(k * r, 2 * math.pi)
            )
    return out


def kernel(t, n: int) -> tuple[int, int, np.ndarray]:
    """(i0, i1, K): the samples [i0, i1) of an axis of ``n`` that positions ``t`` (in samples
    from sample 0) need, and the (len(t), i1 − i0) float32 matrix that interpolates them (a
    sinc at the samples' Nyquist frequency under a Kaiser window of TAPS a side; samples
    beyond the axis are zero)."""
    t = np.asarray(t, np.float64)
    i0 = max(math.floor(t.min()) - TAPS + 1, 0)
    i1 = min(math.floor(t.max()) + TAPS + 1, n)
    if i1 <= i0:
        return i0, i0, np.zeros((len(t), 0), np.float32)
    d = t[:, None] - np.arange(i0, i1)[None, :]
    taper = np.i0(BETA * np.sqrt(np.clip(1 - (d / TAPS) ** 2, 0, 1))) / np.i0(BETA)
    return i0, i1, np.where(np.abs(d) < TAPS, np.sinc(d) * taper, 0).astype(np.float32)


BETA = 0.1102 * (-20 * math.log10(RIPPLE) - 8.7)  # Kaiser's rule for the stop band's leak


def _carrier_plate(h: Hologram) -> None:
    if not isinstance(h, Hologram) or h.carrier is None:
        raise InputError(
            "a carrier plate is needed (a complex plate stored against its zone's "
            "carrier, record_plate's)"
        )


def _region(h: Hologram, region) -> tuple[float, float, float, float]:
    if region is None:
        return window(h)
    x0, y0, x1, y1 = validate.vector("region", region, 4, "m")
    if not (x0 <= x1 and y0 <= y1):
        raise InputError(
            f"region must be (x0, y0, x1, y1) [m] with x0 <= x1 and y0 <= y1; got {list(region)!r}"[
                :300
            ]
        )
    return float(x0), float(y0), float(x1), float(y1)


def _grid(lo: float, hi: float, pitch: float) -> np.ndarray:
    """Sample centres ``pitch`` apart covering [lo, hi], centred on its middle."""
    n = math.ceil((hi - lo) / pitch - 1e-9) + 1
    return (lo + hi) / 2 + (np.arange(n) - (n - 1) / 2) * pitch


def _translation(x: float, y: float) -> np.ndarray:
    m = np.eye(4)
    m[:2, 3] = x, y
    return m


def _full_band(h: Hologram, channel: int, pitch, region) -> Field:
    """A plate without a carrier: its samples (the object wave, centred on the plate) cut to
    ``region``, at its own pitch."""
    if pitch is not None and validate.pitch("pitch", pitch) != h.pitch:
        raise InputError(
            f"pitch: a plate without a carrier holds its object wave at its own "
            f"pitch ({h.pitch:.6g} m); holo_core.resample resamples it"
        )
    rows, cols = h.shape
    x = (np.arange(cols) - (cols - 1) / 2) * h.pitch
    y = (np.arange(rows) - (rows - 1) / 2) * h.pitch
    x0, y0, x1, y1 = (x[0], y[0], x[-1], y[-1]) if region is None else _region(h, region)
    c0, c1 = np.searchsorted(x, x0 - 1e-9 * h.pitch), np.searchsorted(x, x1 + 1e-9 * h.pitch)
    r0, r1 = np.searchsorted(y, y0 - 1e-9 * h.pitch), np.searchsorted(y, y1 + 1e-9 * h.pitch)
    if c1 <= c0 or r1 <= r0:
        raise InputError(f"region {[x0, y0, x1, y1]} [m] holds no sample of the plate")
    samples = np.asarray(h.object_wave[channel, r0:r1, c0:c1], np.complex64)
    pose = np.asarray(h.plate, np.float64) @ _translation(
        (x[c0] + x[c1 - 1]) / 2, (y[r0] + y[r1 - 1]) / 2
    )
    return Field(samples=samples, wavelength=h.wavelengths[channel], pitch=h.pitch, pose=pose)
