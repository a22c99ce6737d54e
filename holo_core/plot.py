"""Plots with physical axes, for notebooks: amplitude, phase, intensity, spectra, holograms and
rendered views. Needs matplotlib (the optional extra ``plot``: ``pip install 'holo[plot]'``).

Fields are drawn as the plane they sample, y upwards (``origin='lower'``): column j at
x = (j − (W−1)/2)·pitch, row i at y = (i − (H−1)/2)·pitch, each pixel a pitch wide, in the
length unit that reads best (nm, µm, mm, m). Spectra are drawn against the spatial
frequencies fx, fy [1/mm] (``numpy.fft.fftfreq`` of the grid, centred). Views keep their row 0
at the top, in field angles [°] when their camera is given.

Each function takes a 2-D array with its ``pitch`` [m] (NumPy or an OpenCL device array, read
back), or an object that carries its optics (a :class:`~holo_core.scene.field.Field`, whose
pitch and wavelength it reads); it draws on ``ax`` (a new figure's axes by default) and
returns the ``AxesImage``. Extra keywords go to ``imshow``.
"""

from __future__ import annotations

import math

import numpy as np

from . import preview, validate
from .scene.hologram import Hologram
from .validate import InputError

try:
    import matplotlib.pyplot as plt
except ImportError as e:  # the optional extra
    raise ImportError("holo_core.plot needs matplotlib: pip install 'holo[plot]'") from e

__all__ = ["amplitude", "hologram", "intensity", "phase", "spectrum", "view"]
_UNITS = (("m", 1.0), ("mm", 1e-3), ("µm", 1e-6), ("nm", 1e-9))


def amplitude(field, pitch=None, *, ax=None, colorbar=True, **imshow):
    """The amplitude |U| of a field against x, y.

    Parameters
    ----------
    field : (H, W) array, device array or Field
        A complex field (NumPy, or an OpenCL device array read back), or a
        :class:`~holo_core.Field` that carries its pitch.
    pitch : float, optional
        Sample spacing [m] of an array (a Field carries its own).
    ax : matplotlib Axes, optional
        Where to draw (default: a new figure's axes).
    colorbar : bool
        Add a colour bar with the quantity's name.
    **imshow
        Further keywords for ``imshow`` (``cmap``, ``vmin``, …).

    Returns
    -------
    matplotlib.image.AxesImage

    Raises
    ------
    InputError
        Where an array comes without ``pitch``, a Field with one, or the field is not 2-D.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import numpy as np
    >>> from holo_core.plot import amplitude
    >>> image = amplitude(np.ones((64, 64), complex), pitch=2e-6)
    >>> image.axes.get_xlabel(), [float(v) for v in image.get_extent()]   # ±32 pitches
    ('x [µm]', [-64.0, 64.0, -64.0, 64.0])
    """
    u, p, _ = _field(field, pitch)
    return _plane(np.abs(u), p, ax, "amplitude |U|", colorbar, imshow)


def intensity(field, pitch=None, *, ax=None, colorbar=True, **imshow):
    """The intensity |U|² of a complex field (or a real intensity) against x, y.

    Parameters
    ----------
    field : (H, W) array, device array or Field
        A complex field (NumPy, or an OpenCL device array read back), or a
        :class:`~holo_core.Field` that carries its pitch.
    pitch : float, optional
        Sample spacing [m] of an array (a Field carries its own).
    ax : matplotlib Axes, optional
        Where to draw (default: a new figure's axes).
    colorbar : bool
        Add a colour bar with the quantity's name.
    **imshow
        Further keywords for ``imshow`` (``cmap``, ``vmin``, …).

    Returns
    -------
    matplotlib.image.AxesImage

    Raises
    ------
    InputError
        Where an array comes without ``pitch``, a Field with one, or the field is not 2-D.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import numpy as np
    >>> from holo_core.plot import intensity
    >>> image = intensity(np.ones((64, 64), complex), pitch=2e-6)
    >>> image.axes.get_xlabel(), [float(v) for v in image.get_extent()]   # ±32 pitches
    ('x [µm]', [-64.0, 64.0, -64.0, 64.0])
    """
    u, p, _ = _field(field, pitch)
    return _plane(np.abs(u) ** 2, p, ax, "intensity |U|²", colorbar, imshow)


def phase(field, pitch=None, *, ax=None, threshold=1e-3, colorbar=True, **imshow):
    """The phase arg U [rad] in (−π, π] against x, y.

    Parameters
    ----------
    field : (H, W) array, device array or Field
        A complex field (NumPy, or an OpenCL device array read back), or a
        :class:`~holo_core.Field` that carries its pitch.
    pitch : float, optional
        Sample spacing [m] of an array (a Field carries its own).
    threshold : float
        Blank (NaN) where |U| < ``threshold``·max |U|: the phase of nothing is noise.
    ax : matplotlib Axes, optional
        Where to draw (default: a new figure's axes).
    colorbar : bool
        Add a colour bar with the quantity's name.
    **imshow
        Further keywords for ``imshow`` (``cmap``, ``vmin``, …).

    Returns
    -------
    matplotlib.image.AxesImage

    Raises
    ------
    InputError
        Where an array comes without ``pitch``, a Field with one, or the field is not 2-D.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import numpy as np
    >>> from holo_core.plot import phase
    >>> image = phase(np.ones((64, 64), complex), pitch=2e-6)
    >>> image.axes.get_xlabel(), [float(v) for v in image.get_extent()]   # ±32 pitches
    ('x [µm]', [-64.0, 64.0, -64.0, 64.0])
    """
    u, p, _ = _field(field, pitch)
    a = np.abs(u)
    ph = np.where(a >= threshold * a.max(), np.angle(u), np.nan) if a.size else np.angle(u)
    kw = {"cmap": "twilight", "vmin": -math.pi, "vmax": math.pi, **imshow}
    return _plane(ph, p, ax, "phase [rad]", colorbar, kw)


def spectrum(field, pitch=None, *, ax=None, log=True, colorbar=True, **imshow):
    """The power spectrum |FFT U|² against the spatial frequencies fx, fy [1/mm].

    Zero frequency at the centre (``numpy.fft.fftfreq`` of the grid, shifted).

    Parameters
    ----------
    field : (H, W) array, device array or Field
        A complex field (NumPy, or an OpenCL device array read back), or a
        :class:`~holo_core.Field` that carries its pitch.
    pitch : float, optional
        Sample spacing [m] of an array (a Field carries its own).
    log : bool
        In dB of the peak (floored at −120 dB), else linear power.
    ax : matplotlib Axes, optional
        Where to draw (default: a new figure's axes).
    colorbar : bool
        Add a colour bar with the quantity's name.
    **imshow
        Further keywords for ``imshow`` (``cmap``, ``vmin``, …).

    Returns
    -------
    matplotlib.image.AxesImage

    Raises
    ------
    InputError
        Where an array comes without ``pitch``, a Field with one, or the field is not 2-D.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import numpy as np
    >>> from holo_core.plot import spectrum
    >>> image = spectrum(np.ones((64, 64), complex), pitch=2e-6)
    >>> image.axes.get_xlabel(), round(image.get_extent()[0], 1)   # −1/(2·pitch), a bin wide
    ('fx [1/mm]', -253.9)
    """
    u, p, _ = _field(field, pitch)
    s = np.abs(np.fft.fftshift(np.fft.fft2(u))) ** 2
    if log:
        s = 10 * np.log10(np.maximum(s / max(float(s.max()), 1e-300), 1e-12))
    h, w = s.shape
    fx, fy = (np.fft.fftshift(np.fft.fftfreq(n, p)) * 1e-3 for n in (w, h))  # [1/mm]
    dx, dy = (
        (fx[1] - fx[0] if w > 1 else 1 / (p * 1e3)),
        (fy[1] - fy[0] if h > 1 else 1 / (p * 1e3)),
    )
    extent = (fx[0] - dx / 2, fx[-1] + dx / 2, fy[0] - dy / 2, fy[-1] + dy / 2)
    ax = ax or plt.figure().add_subplot()
    image = ax.imshow(s, origin="lower", extent=extent, **{"cmap": "magma", **imshow})
    ax.set_xlabel("fx [1/mm]")
    ax.set_ylabel("fy [1/mm]")
    if colorbar:
        ax.figure.colorbar(image, ax=ax, label="power [dB of peak]" if log else "power")
    return image


def hologram(h, colour: int = 0, *, ax=None, colorbar=True, **imshow):
    """The recorded intensity of one colour of a Hologram against x, y.

    Parameters
    ----------
    h : Hologram
        An intensity hologram, or a complex one (|O|² is drawn).
    colour : int
        Index into its wavelengths; the title names the channel and the wavelength.
    ax : matplotlib Axes, optional
        Where to draw (default: a new figure's axes).
    colorbar : bool
        Add a colour bar with the quantity's name.
    **imshow
        Further keywords for ``imshow`` (``cmap``, ``vmin``, …).

    Returns
    -------
    matplotlib.image.AxesImage

    Raises
    ------
    InputError
        Where ``h`` is not a Hologram or ``colour`` is out of range.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import numpy as np
    >>> from holo_core import Hologram
    >>> from holo_core.plot import hologram
    >>> h = Hologram(intensity=np.ones((1, 64, 64), np.float32), wavelengths=(633e-9,),
    ...              pitch=2e-6)
    >>> hologram(h).axes.get_title()
    'Y at 633 nm'
    """
    if not isinstance(h, Hologram):
        raise InputError(f"h must be a Hologram; got {type(h).__name__}")
    c = validate.index("colour", colour, len(h.wavelengths))
    held = (
        h.intensity
        if getattr(h, "encoding", "intensity") == "intensity"
        else np.abs(h.object_wave) ** 2
    )
    image = _plane(held[c], h.pitch, ax, "intensity", colorbar, {"cmap": "gray", **imshow})
    image.axes.set_title(f"{h.channels[c]} at {preview.length(h.wavelengths[c])}")
    return image


def view(result, *, camera=None, ax=None, **imshow):
    """A rendered view's radiance in sRGB, row 0 at the top.

    Parameters
    ----------
    result : RenderResult
        A view (:func:`holo_core.render_view`'s, :func:`holo_core.render_camera`'s).
    camera : Camera, optional
        Its camera: the axes are then field angles [°] (atan of the view tangents at the
        image's edges), else pixels.
    ax : matplotlib Axes, optional
        Where to draw (default: a new figure's axes).
    **imshow
        Further keywords for ``imshow``.

    Returns
    -------
    matplotlib.image.AxesImage

    Raises
    ------
    InputError
        Where the camera's resolution differs from the view's.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import numpy as np
    >>> from holo_core import Camera, RenderResult, look_at
    >>> from holo_core.plot import view
    >>> cam = Camera(matrix_world=look_at((0, -1, 0), (0, 0, 0)), resolution=(64, 48))
    >>> black = RenderResult(rgb=np.zeros((48, 64, 3)), alpha=np.zeros((48, 64)),
    ...                      depth=np.full((48, 64), np.inf))
    >>> view(black, camera=cam).axes.get_xlabel()
    'x field angle [°]'
    """
    rgb = preview.srgb(np.asarray(result.rgb, np.float64))
    h, w = rgb.shape[:2]
    ax = ax or plt.figure().add_subplot()
    if camera is None:
        extent, labels = (-0.5, w - 0.5, h - 0.5, -0.5), ("column", "row")
    else:
        if tuple(camera.resolution) != (w, h):
            raise InputError(
                f"camera resolution {tuple(camera.resolution)} differs from the view's {w}x{h}"
            )
        tx, ty = camera.pixel_tangents(np.array([0.0, h]), np.array([0.0, w]))
        left, right = np.degrees(np.arctan(tx))
        top, bottom = np.degrees(np.arctan(ty))
        extent, labels = (left, right, bottom, top), ("x field angle [°]", "y field angle [°]")
    image = ax.imshow(rgb, origin="upper", extent=extent, **imshow)
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    return image


def _field(field, pitch):
    """(host array, pitch [m], wavelength [m] or None) of an array or a field-like object."""
    carried = getattr(field, "pitch", None)
    if carried is not None and hasattr(field, "samples"):  # a Field: its optics come with it
        if pitch is not None:
            raise InputError("pitch comes with the field; leave it out")
        px, py = carried
        if not math.isclose(px, py, rel_tol=1e-12):
            raise InputError(
                f"the field's pitch differs in x and y ({px!r}, {py!r}); plot "
                f"an isotropic field or resample it"
            )
        u = field.samples
        if getattr(u, "ndim", 2) != 2:
            raise InputError(
                f"plot one field at a time; this one holds a batch of shape "
                f"{tuple(u.shape)}: index it, field[i]"
            )
        return _host(u), px, getattr(field, "wavelength", None)
    if pitch is None:
        raise InputError("pitch must be given [m] for an array")
    return _host(field), validate.pitch("pitch", pitch), None


def _host(u) -> np.ndarray:
    a = u.get() if hasattr(u, "get") and hasattr(u, "queue") else np.asarray(u)
    if a.ndim != 2 or not a.size:
        raise InputError(f"field must be a 2-D array [rows=y, cols=x]; got shape {a.shape}")
    return a


def _plane(values, pitch, ax, label, colorbar, imshow):
    h, w = values.shape
    unit, scale = next(((n, s) for n, s in _UNITS if max(h, w) * pitch >= 10 * s), _UNITS[-1])
    extent = (
        -w * pitch / 2 / scale,
        w * pitch / 2 / scale,
        -h * pitch / 2 / scale,
        h * pitch / 2 / scale,
    )
    ax = ax or plt.figure().add_subplot()
    image = ax.imshow(values, origin="lower", extent=extent, **{"cmap": "gray", **imshow})
    ax.set_xlabel(f"x [{unit}]")
    ax.set_ylabel(f"y [{unit}]")
    if colorbar:
        ax.figure.colorbar(image, ax=ax, label=label)
    return image
