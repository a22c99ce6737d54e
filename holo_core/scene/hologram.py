"""The hologram: recorded holograms of one scene, one per wavelength, with their optics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import preview, validate
from ..validate import InputError
from .plate import ViewingZone

CHANNEL_ROLES = ("R", "G", "B", "Y", "Z")
ENCODINGS = ("complex", "intensity")
MAX_CHANNELS = 16


@dataclass(frozen=True, eq=False, kw_only=True)
class Hologram:
    """Recorded holograms of one scene, one per wavelength.

    encoding : 'complex' (the default for plates: the object wave O itself, ``object_wave``,
        with no reference and no carrier) or 'intensity' (H = |O + R|², Eq. 19: what a
        display or a print shows; its reconstruction suppresses the DC and twin terms)
    intensity : (C, H, W) float32, H = |O + R|² per colour, [row, col] = [y, x]; None for a
        complex hologram
    wavelengths : C wavelengths [m]
    pitch : sample spacing [m]
    reference_angle, reference_azimuth : the reference wave's ϑ and φ [rad] (Eq. 4)
    reference_amplitudes : |R| per colour [field units]
    object_wave : (C, H, W) complex64, the object wave O on the plate; None for an intensity
        hologram that does not keep it
    plate : (4, 4) hologram-to-world pose (the hologram plane is z = 0 of its frame) [m]
    bounds : (2, 3) the objects' min and max corners in the hologram frame [m]
    band : sin θ of the object wave's cone, the band its reconstruction keeps (0: all)
    channels : one role per wavelength: 'R', 'G', 'B' (or 'Y') colour, 'Z' the depth partner
        λ2 of the colour channels at channel 0's wavelength λ1 (Sect. VII-C), every emitter
        at unit intensity (for holograms recorded for one camera, times its surface's cosine
        towards it): its image is the surfaces' coverage of each pixel
    point_density : emitters per m² of surface, which calibrates radiance (0: unknown)
    zone : the :class:`~holo_core.scene.plate.ViewingZone` it was recorded for (the plate's
        frame), or None (unknown: an acquired or earlier hologram)

    The samples are arrays indexed [channel, row, col]; nothing here assumes they are held in
    memory at once (a view reads the window of rows and columns it needs, so chunked arrays of
    a tiled store serve as well).
    """

    intensity: np.ndarray | None = None
    wavelengths: tuple
    pitch: float
    reference_angle: float = 0.0
    reference_azimuth: float = 0.0
    reference_amplitudes: tuple = ()
    object_wave: np.ndarray | None = None
    plate: np.ndarray = field(default_factory=lambda: np.eye(4))
    bounds: np.ndarray = field(default_factory=lambda: np.zeros((2, 3)))
    band: float = 0.0
    channels: tuple = ()
    point_density: float = 0.0
    encoding: str = "intensity"
    zone: ViewingZone | None = None

    def __post_init__(self):
        """Every field checked against what its file may hold (the reader's schema), so that
        a hologram that exists can be written and read back."""
        wavelengths = self.wavelengths
        if np.ndim(wavelengths) != 1 or not 1 <= len(wavelengths) <= MAX_CHANNELS:
            raise InputError(f"wavelengths must be 1 to {MAX_CHANNELS} wavelengths [m]; "
                             f"got {wavelengths!r}")
        wavelengths = tuple(validate.wavelength("wavelengths", w) for w in wavelengths)
        object.__setattr__(self, "wavelengths", wavelengths)
        object.__setattr__(self, "pitch", validate.pitch("pitch", self.pitch))
        try:
            object.__setattr__(self, "channels", tuple(self.channels or ()))
        except TypeError:
            raise InputError(f"channels must be a sequence of {'/'.join(CHANNEL_ROLES)}; got "
                             f"{self.channels!r}") from None
        if not self.channels:
            names = ("R", "G", "B") if len(wavelengths) == 3 else ("Y",) * MAX_CHANNELS
            object.__setattr__(self, "channels", names[:len(wavelengths)])
        if len(self.channels) != len(wavelengths) or \
                not all(c in CHANNEL_ROLES for c in self.channels):
            raise InputError(f"channels must name each of the {len(wavelengths)} wavelengths "
                             f"by one of {'/'.join(CHANNEL_ROLES)}; got {self.channels!r}")
        if "Z" in self.channels[:1]:
            raise InputError("channel 0 must be a colour channel (the depth pair's λ1)")
        object.__setattr__(self, "plate", validate.rigid_pose("plate", self.plate))
        self._check_samples(len(wavelengths))
        self._check_optics()
        if self.zone is not None and not isinstance(self.zone, ViewingZone):
            raise InputError(f"zone must be a ViewingZone or None; got {type(self.zone).__name__}")

    def _check_samples(self, count):
        """The encoding's arrays: the intensity (C, H, W) of an intensity hologram, the object
        wave of a complex one; both, when present, of one shape."""
        if self.encoding not in ENCODINGS:
            raise InputError(f"encoding must be one of {', '.join(map(repr, ENCODINGS))}; got "
                             f"{self.encoding!r}"[:300])
        held = self.intensity if self.encoding == "intensity" else self.object_wave
        name = "intensity" if self.encoding == "intensity" else "object_wave"
        if np.ndim(held) != 3 or np.shape(held)[0] != count:
            raise InputError(f"{name} must be (C, H, W) with C = {count} wavelengths for an "
                             f"{self.encoding} hologram; got shape {np.shape(held)}")
        for other, other_name in ((self.intensity, "intensity"), (self.object_wave,
                                                                 "object_wave")):
            if other is not None and np.shape(other) != np.shape(held):
                raise InputError(f"{other_name} must be shaped as the {name} "
                                 f"{np.shape(held)}; got {np.shape(other)}")

    def _check_optics(self):
        angle = validate.finite("reference_angle", self.reference_angle, "rad")
        if not 0 <= angle < math.pi / 2:
            raise InputError(f"reference_angle must be in [0, π/2) rad; got "
                             f"{self.reference_angle!r}")
        validate.finite("reference_azimuth", self.reference_azimuth, "rad")
        amplitudes = self.reference_amplitudes
        if np.ndim(amplitudes) != 1 or len(amplitudes) not in (0, len(self.wavelengths)):
            raise InputError(f"reference_amplitudes must be {len(self.wavelengths)} numbers "
                             f"> 0 (|R| per wavelength) or empty; got {amplitudes!r}")
        for a in amplitudes:  # R'·H / |R|² divides by them (Eq. 18)
            validate.positive("reference_amplitudes", a)
        band = validate.finite("band", self.band)
        if not 0 <= band < 1:
            raise InputError(f"band must be in [0, 1) (sin θ of the object wave's cone; 0: "
                             f"all); got {self.band!r}")
        try:
            bounds = np.asarray(self.bounds, np.float64)
        except (TypeError, ValueError):
            bounds = np.zeros(0)
        if bounds.shape != (2, 3) or not np.isfinite(bounds).all() or \
                (bounds[0] > bounds[1]).any():
            raise InputError(f"bounds must be two finite corners (min, max) of (x, y, z) [m], "
                             f"min <= max; got {self.bounds!r}")
        density = validate.finite("point_density", self.point_density, "1/m²")
        if density < 0:
            raise InputError(f"point_density must be >= 0 [1/m²]; got {self.point_density!r}")

    def colour_channels(self) -> list[int]:
        return [i for i, c in enumerate(self.channels) if c != "Z"]

    def depth_channel(self) -> int | None:
        """The index of λ2 = ε·λ1 (λ1: channel 0's wavelength), or None."""
        return self.channels.index("Z") if "Z" in self.channels else None

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of samples."""
        held = self.intensity if self.encoding == "intensity" else self.object_wave
        return tuple(held.shape[1:])

    @property
    def size(self) -> tuple[float, float]:
        """Physical (width, height) [m]."""
        return self.shape[1] * self.pitch, self.shape[0] * self.pitch

    def __repr__(self) -> str:
        """One line: samples, channels and wavelengths, pitch, encoding, reference; no data."""
        h, w = self.shape
        encoding = getattr(self, "encoding", "intensity")
        count = len(self.wavelengths)
        channels = (f"{count} channel{'s' * (count > 1)} {'/'.join(self.channels)} at "
                    f"{preview.lengths(self.wavelengths)}")
        parts = [f"{h}x{w}", channels, f"pitch {preview.length(self.pitch)}", encoding]
        if self.reference_angle:
            parts.append(f"reference {self.reference_angle:.4g} rad at azimuth "
                         f"{self.reference_azimuth:.4g} rad")
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
        held = self.intensity if getattr(self, "encoding", "intensity") == "intensity" \
            else np.abs(self.object_wave) ** 2
        rgb = [self.channels.index(c) for c in "RGB" if c in self.channels]
        if len(rgb) == 3:
            image = np.stack([preview.thumbnail(held[c]) for c in rgb], -1)
        else:
            image = preview.thumbnail(held[0])
        return preview.png(preview.normalised(image))
