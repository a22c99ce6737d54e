"""The hologram: recorded holograms of one scene, one per wavelength, with their optics.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import validate
from ..validate import InputError


@dataclass(frozen=True, eq=False, kw_only=True)
class Hologram:
    """Recorded holograms of one scene, one per wavelength.

    intensity : (C, H, W) float32, H = |O + R|² per colour, [row, col] = [y, x]
    wavelengths : C wavelengths [m]
    pitch : sample spacing [m]
    reference_angle, reference_azimuth : the reference wave's ϑ and φ [rad] (Eq. 4)
    reference_amplitudes : |R| per colour [field units]
    object_wave : (C, H, W) complex64 or None
    plate : (4, 4) hologram-to-world pose (the hologram plane is z = 0 of its frame) [m]
    bounds : (2, 3) the objects' min and max corners in the hologram frame [m]
    band : sin θ of the object wave's cone, the band its reconstruction keeps (0: all)
    channels : one role per wavelength: 'R', 'G', 'B' (or 'Y') colour, 'Z' the depth partner
        λ2 of the colour channels at channel 0's wavelength λ1 (Sect. VII-C), every emitter
        at unit intensity times its surface's cosine towards the camera (its image is the
        surfaces' coverage of each pixel)
    point_density : emitters per m² of surface, which calibrates radiance (0: unknown)
    """

    intensity: np.ndarray
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

    def __post_init__(self):
        if not self.channels:
            names = ("R", "G", "B") if len(self.wavelengths) == 3 else ("Y",) * 99
            object.__setattr__(self, "channels", names[:len(self.wavelengths)])
        if len(self.channels) != len(self.wavelengths):
            raise InputError(f"channels must name each of the {len(self.wavelengths)} "
                             f"wavelengths; got {self.channels!r}")
        if "Z" in self.channels[:1]:
            raise InputError("channel 0 must be a colour channel (the depth pair's λ1)")
        object.__setattr__(self, "plate", validate.rigid_pose("plate", self.plate))
        validate.positive("pitch", self.pitch, "m")
        for lam in self.wavelengths:
            validate.positive("wavelengths", lam, "m")
        if np.ndim(self.intensity) != 3 or len(self.intensity) != len(self.wavelengths):
            raise InputError(f"intensity must be (C, H, W) with C = {len(self.wavelengths)} "
                             f"wavelengths; got shape {np.shape(self.intensity)}")

    def colour_channels(self) -> list[int]:
        return [i for i, c in enumerate(self.channels) if c != "Z"]

    def depth_channel(self) -> int | None:
        """The index of λ2 = ε·λ1 (λ1: channel 0's wavelength), or None."""
        return self.channels.index("Z") if "Z" in self.channels else None

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.intensity.shape[1:])

    @property
    def size(self) -> tuple[float, float]:
        """Physical (width, height) [m]."""
        return self.shape[1] * self.pitch, self.shape[0] * self.pitch
