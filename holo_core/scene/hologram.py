"""The hologram: recorded holograms of one scene, one per wavelength, with their optics."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .. import preview, validate
from ..validate import InputError, shown
from .plate import Carrier, ViewingZone

CHANNEL_ROLES = ("R", "G", "B", "Y", "Z")
ENCODINGS = ("complex", "intensity")
MAX_CHANNELS = 16


@dataclass(frozen=True, eq=False, kw_only=True)
class HologramInfo:
    """What a hologram is, apart from its samples: the one description that the file readers,
    the tiled store, the recorder's early checks and :class:`Hologram` share, every field
    checked here and nowhere else (a file's reader converts its JSON, then builds this).

    wavelengths : C wavelengths [m], 1 to 16
    pitch : sample spacing [m]
    shape : (rows, cols) of samples per wavelength
    encoding : 'complex' (the object wave O itself, no reference and no carrier) or
        'intensity' (H = |O + R|², Eq. 19)
    keeps_object_wave : whether the object wave is held (a complex hologram's samples are
        it; an intensity hologram may keep it beside); None: as the encoding has it
    reference_angle, reference_azimuth : the reference wave's ϑ and φ [rad] (Eq. 4)
    reference_amplitudes : |R| per colour [field units], or none
    plate : (4, 4) hologram-to-world pose (the hologram plane is z = 0 of its frame) [m]
    bounds : (2, 3) the objects' min and max corners in the hologram frame [m]
    band : sin θ of the object wave's cone, the band its reconstruction keeps (0: all)
    channels : one role per wavelength: 'R', 'G', 'B' (or 'Y') colour, 'Z' the depth partner
        λ2 of the colour channels at channel 0's wavelength λ1 (Sect. VII-C), every emitter
        at unit intensity: its image is the surfaces' coverage of each pixel
    point_density : emitters per m² of surface, which calibrates radiance (0: unknown)
    zone : the :class:`~holo_core.scene.plate.ViewingZone` it was recorded for (the plate's
        frame), or None (unknown: an acquired or earlier hologram)
    carrier : the :class:`~holo_core.scene.plate.Carrier` a complex plate's samples are stored
        against (the object wave is samples·exp(−ik|x − carrier.centre|), sample (0, 0) at
        carrier.origin; ``band`` is then the samples' band around it), or None (the samples
        are the object wave, centred on the plate)
    recording : the digest of the recording the samples are (what they were recorded from:
        the emitters, the plate, its zone and looks; the name a plate file is known by), so
        that a reader expecting one recording refuses another's under its name; '' (unknown:
        an acquired, imported or earlier hologram)
    """

    wavelengths: tuple
    pitch: float
    shape: tuple
    encoding: str = "intensity"
    keeps_object_wave: bool | None = None
    reference_angle: float = 0.0
    reference_azimuth: float = 0.0
    reference_amplitudes: tuple = ()
    plate: np.ndarray = field(default_factory=lambda: np.eye(4))
    bounds: np.ndarray = field(default_factory=lambda: np.zeros((2, 3)))
    band: float = 0.0
    channels: tuple = ()
    point_density: float = 0.0
    zone: ViewingZone | None = None
    carrier: Carrier | None = None
    recording: str = ""

    def __post_init__(self):
        wavelengths = self.wavelengths
        if np.ndim(wavelengths) != 1 or not 1 <= len(wavelengths) <= MAX_CHANNELS:
            raise InputError(
                f"wavelengths must be 1 to {MAX_CHANNELS} wavelengths [m]; got {shown(wavelengths)}"
            )
        self._set("wavelengths", tuple(validate.wavelength("wavelengths", w) for w in wavelengths))
        self._set("pitch", validate.pitch("pitch", self.pitch))
        try:
            rows, cols = (validate.integer("shape", n, 0) for n in self.shape)
        except (TypeError, ValueError):
            raise InputError(
                f"shape must be two integers >= 0 (rows, cols); got {self.shape!r}"[:300]
            ) from None
        self._set("shape", (rows, cols))
        validate.choice("encoding", self.encoding, ENCODINGS)
        kept = (
            self.encoding == "complex" if self.keeps_object_wave is None else self.keeps_object_wave
        )
        if not isinstance(kept, (bool, np.bool_)) or (self.encoding == "complex" and not kept):
            raise InputError(
                f"keeps_object_wave must be true or false (true for a complex "
                f"hologram: its samples are the object wave); got "
                f"{self.keeps_object_wave!r}"
            )
        self._set("keeps_object_wave", bool(kept))
        self._check_channels()
        validate.digest("recording", self.recording)
        self._set("plate", validate.rigid_pose("plate", self.plate))
        self._check_optics()
        if self.zone is not None and not isinstance(self.zone, ViewingZone):
            raise InputError(f"zone must be a ViewingZone or None; got {type(self.zone).__name__}")
        if self.carrier is not None and (
            not isinstance(self.carrier, Carrier) or self.encoding != "complex"
        ):
            raise InputError(
                f"carrier must be a Carrier of a complex hologram, or None; got "
                f"{type(self.carrier).__name__} on an {self.encoding} hologram"
            )

    def _set(self, name, value):
        object.__setattr__(self, name, value)

    def _check_channels(self):
        count = len(self.wavelengths)
        try:
            self._set("channels", tuple(self.channels or ()))
        except TypeError:
            raise InputError(
                f"channels must be a sequence of {'/'.join(CHANNEL_ROLES)}; got {self.channels!r}"
            ) from None
        if not self.channels:
            names = ("R", "G", "B") if count == 3 else ("Y",) * MAX_CHANNELS
            self._set("channels", names[:count])
        if len(self.channels) != count or not all(c in CHANNEL_ROLES for c in self.channels):
            raise InputError(
                f"channels must name each of the {count} wavelengths by one of "
                f"{'/'.join(CHANNEL_ROLES)}; got {self.channels!r}"
            )
        if "Z" in self.channels[:1]:
            raise InputError(
                "channels must begin with a colour channel (the depth pair's λ1); "
                f"got {self.channels!r}"
            )

    def _check_optics(self):
        angle = validate.finite("reference_angle", self.reference_angle, "rad")
        if not 0 <= angle < math.pi / 2:
            raise InputError(
                f"reference_angle must be in [0, π/2) rad; got {self.reference_angle!r}"
            )
        self._set("reference_angle", angle)
        self._set(
            "reference_azimuth", validate.finite("reference_azimuth", self.reference_azimuth, "rad")
        )
        amplitudes, count = self.reference_amplitudes, len(self.wavelengths)
        try:  # R'·H / |R|² divides by them (Eq. 18)
            values = tuple(float(a) for a in amplitudes) if np.ndim(amplitudes) == 1 else None
        except (TypeError, ValueError):
            values = None
        if (
            values is None
            or len(values) not in (0, count)
            or not all(math.isfinite(a) and a > 0 for a in values)
        ):
            raise InputError(
                f"reference_amplitudes must be {count} numbers > 0 (|R| per "
                f"wavelength) or none; got {amplitudes!r}"[:300]
            )
        self._set("reference_amplitudes", values)
        band = validate.finite("band", self.band)
        if not 0 <= band < 1:
            raise InputError(
                f"band must be in [0, 1) (sin θ of the object wave's cone; 0: "
                f"all); got {shown(self.band)}"
            )
        self._set("band", band)
        try:
            bounds = np.asarray(self.bounds, np.float64)
        except (TypeError, ValueError):
            bounds = np.zeros(0)
        if bounds.shape != (2, 3) or not np.isfinite(bounds).all() or (bounds[0] > bounds[1]).any():
            raise InputError(
                f"bounds must be two finite corners (min, max) of (x, y, z) [m], "
                f"min <= max; got {shown(self.bounds)}"
            )
        self._set("bounds", bounds)
        density = validate.finite("point_density", self.point_density, "1/m²")
        if density < 0:
            raise InputError(f"point_density must be >= 0 [1/m²]; got {shown(self.point_density)}")
        self._set("point_density", density)

    def colour_channels(self) -> list[int]:
        return [i for i, c in enumerate(self.channels) if c != "Z"]

    def depth_channel(self) -> int | None:
        """The index of λ2 = ε·λ1 (λ1: channel 0's wavelength), or None."""
        return self.channels.index("Z") if "Z" in self.channels else None

    @property
    def row_pitch(self) -> float:
        """The rows' spacing [m]: the pitch, or a carrier plate's own."""
        return self.pitch if self.carrier is None else self.carrier.row_pitch

    @property
    def size(self) -> tuple[float, float]:
        """Physical (width, height) [m]."""
        return self.shape[1] * self.pitch, self.shape[0] * self.row_pitch


# the fields a hologram's description holds beside its shape (which its samples give)
DESCRIPTION = (
    "wavelengths",
    "pitch",
    "encoding",
    "reference_angle",
    "reference_azimuth",
    "reference_amplitudes",
    "plate",
    "bounds",
    "band",
    "channels",
    "point_density",
    "zone",
    "carrier",
    "recording",
)


def _described(name):
    return property(
        lambda self: getattr(self.info, name), doc=f"The hologram's {name} (:class:`HologramInfo`)."
    )


@dataclass(frozen=True, eq=False, init=False)
class Hologram:
    """Recorded holograms of one scene, one per wavelength: their description and samples.

    The description (:class:`HologramInfo`, ``info``) has its fields read as the hologram's
    own: ``h.pitch``.

    Parameters
    ----------
    intensity : (C, H, W) float32 array, optional
        H = ``|O + R|²`` per colour (Eq. 16), [row, col] = [y, x]; None for a complex
        hologram.
    object_wave : (C, H, W) complex64 array, optional
        The object wave O on the plate; None for an intensity hologram that does not keep it.
    info : HologramInfo, optional
        A description checked already (a file's, a store's), whose samples are then checked
        against it alone.
    **description
        Otherwise the description's fields as keywords (``wavelengths`` [m], ``pitch`` [m],
        ...), checked by :class:`HologramInfo`.

    Raises
    ------
    InputError
        Where a description field is unknown or out of range, or the samples do not match it.

    Notes
    -----
    The samples are arrays indexed [channel, row, col]; nothing here assumes they are held in
    memory at once (a view reads the window of rows and columns it needs, so chunked arrays of
    a tiled store serve as well).

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Hologram
    >>> h = Hologram(intensity=np.ones((1, 64, 64), np.float32), wavelengths=(633e-9,),
    ...              pitch=2e-6)
    >>> h.intensity.shape, h.pitch
    ((1, 64, 64), 2e-06)
    """

    intensity: np.ndarray | None
    object_wave: np.ndarray | None
    info: HologramInfo

    def __init__(
        self, *, intensity=None, object_wave=None, info: HologramInfo | None = None, **description
    ):
        unknown = set(description) - set(DESCRIPTION)
        if unknown:
            raise TypeError(f"Hologram() got unexpected keyword arguments {sorted(unknown)}")
        if info is not None and not isinstance(info, HologramInfo):
            raise InputError(f"info must be a HologramInfo; got {type(info).__name__}")
        encoding = description.get("encoding", "intensity" if info is None else info.encoding)
        held, name = (
            (intensity, "intensity") if encoding == "intensity" else (object_wave, "object_wave")
        )
        if np.ndim(held) != 3:
            raise InputError(
                f"{name} must be (C, H, W), one (H, W) image per wavelength, for "
                f"an {encoding} hologram; got shape {np.shape(held)}"[:300]
            )
        samples = {"shape": tuple(np.shape(held)[1:]), "keeps_object_wave": object_wave is not None}
        if info is None:
            info = HologramInfo(**samples, **description)
        else:  # a described hologram's samples change its description only where they differ
            changed = {k: v for k, v in samples.items() if getattr(info, k) != v}
            if changed or description:
                info = replace(info, **changed, **description)
        object.__setattr__(self, "intensity", intensity)
        object.__setattr__(self, "object_wave", object_wave)
        object.__setattr__(self, "info", info)
        count = len(info.wavelengths)
        if np.shape(held)[0] != count:
            raise InputError(
                f"{name} must be (C, H, W) with C = {count} wavelengths for an "
                f"{encoding} hologram; got shape {np.shape(held)}"
            )
        for other, other_name in ((intensity, "intensity"), (object_wave, "object_wave")):
            if other is not None and np.shape(other) != np.shape(held):
                raise InputError(
                    f"{other_name} must be shaped as the {name} "
                    f"{np.shape(held)}; got {np.shape(other)}"
                )

    wavelengths = _described("wavelengths")
    pitch = _described("pitch")
    encoding = _described("encoding")
    reference_angle = _described("reference_angle")
    reference_azimuth = _described("reference_azimuth")
    reference_amplitudes = _described("reference_amplitudes")
    plate = _described("plate")
    bounds = _described("bounds")
    band = _described("band")
    channels = _described("channels")
    point_density = _described("point_density")
    zone = _described("zone")
    carrier = _described("carrier")
    recording = _described("recording")
    row_pitch = _described("row_pitch")
    shape = _described("shape")
    size = _described("size")

    def colour_channels(self) -> list[int]:
        return self.info.colour_channels()

    def depth_channel(self) -> int | None:
        """The index of λ2 = ε·λ1 (λ1: channel 0's wavelength), or None."""
        return self.info.depth_channel()

    def __repr__(self) -> str:
        """One line: samples, channels and wavelengths, pitch, encoding, reference; no data."""
        h, w = self.shape
        encoding = self.encoding
        count = len(self.wavelengths)
        channels = (
            f"{count} channel{'s' * (count > 1)} {'/'.join(self.channels)} at "
            f"{preview.lengths(self.wavelengths)}"
        )
        parts = [f"{h}x{w}", channels, f"pitch {preview.length(self.pitch)}", encoding]
        if self.reference_angle:
            parts.append(
                f"reference {self.reference_angle:.4g} rad at azimuth "
                f"{self.reference_azimuth:.4g} rad"
            )
        if self.object_wave is not None and encoding == "intensity":
            parts.append("object wave kept")
        if self.band:
            parts.append(f"band sin θ {self.band:.3g}")
        held = self.intensity if encoding == "intensity" else self.object_wave
        where = "on the host" if isinstance(held, np.ndarray) else f"in {type(held).__name__}"
        return f"Hologram({', '.join(parts)}, {where})"

    def _repr_png_(self) -> bytes:
        """A notebook's picture: the intensity (|O|² of a complex hologram) of the R, G, B
        channels as colour, else of channel 0, normalised, at most 512 pixels a side."""
        held = self.intensity if self.encoding == "intensity" else np.abs(self.object_wave) ** 2
        rgb = [self.channels.index(c) for c in "RGB" if c in self.channels]
        if len(rgb) == 3:
            image = np.stack([preview.thumbnail(held[c]) for c in rgb], -1)
        else:
            image = preview.thumbnail(held[0])
        return preview.png(preview.normalised(image))
