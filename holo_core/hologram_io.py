"""The hologram and its file: OpenEXR, float32 channels per wavelength, metadata as JSON.

Channels, for colour c = 0, 1, ...: ``c<c>.H`` the intensity hologram, and optionally
``c<c>.O.re`` / ``c<c>.O.im`` the complex object wave. The header attribute ``holo`` holds
the metadata (see :func:`metadata`); files are written atomically and read back bit-exactly.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import __version__, validate
from .image_files import write_exr

FORMAT = "holo-hologram"
FORMAT_VERSION = 2  # 2: the depth partner 'Z' records every emitter at unit intensity
EXR_MAGIC = b"\x76\x2f\x31\x01"


class HologramFileError(ValueError):
    """A hologram file that cannot be read; the message names the file and the problem."""


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
            raise ValueError(f"channels must name each of the {len(self.wavelengths)} "
                             f"wavelengths; got {self.channels!r}")
        if "Z" in self.channels[:1]:
            raise ValueError("channel 0 must be a colour channel (the depth pair's λ1)")

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


def metadata(h: Hologram) -> dict:
    return {
        "format": FORMAT, "format_version": FORMAT_VERSION, "software": f"holo {__version__}",
        "wavelengths_m": list(map(float, h.wavelengths)), "pitch_m": float(h.pitch),
        "size_px": list(h.shape), "plate_to_world": np.asarray(h.plate).ravel().tolist(),
        "reference": {"angle_rad": float(h.reference_angle),
                      "azimuth_rad": float(h.reference_azimuth),
                      "amplitudes": list(map(float, h.reference_amplitudes))},
        "bounds_m": np.asarray(h.bounds).tolist(), "object_wave": h.object_wave is not None,
        "band_sin": float(h.band), "channels": list(h.channels),
        "point_density_per_m2": float(h.point_density),
    }


def write_hologram(path, h: Hologram) -> Path:
    """Write ``h`` to ``path`` (.exr) through a temporary file and a rename."""
    channels = {}
    for c in range(len(h.wavelengths)):
        channels[f"c{c}.H"] = h.intensity[c]
        if h.object_wave is not None:
            channels[f"c{c}.O.re"] = h.object_wave[c].real
            channels[f"c{c}.O.im"] = h.object_wave[c].imag
    write_exr(path, channels, holo=json.dumps(metadata(h)))
    return path


def read_hologram(path) -> Hologram:
    """Read a hologram written by :func:`write_hologram`; :class:`HologramFileError` if the
    file is missing, not an EXR, truncated, of an unknown format version or lacks a channel."""
    import OpenEXR
    path = Path(path)
    _check_exr(path)
    try:
        with OpenEXR.File(str(path)) as f:
            header = f.header()
            meta = _meta(path, header)
            names = f.channels()
            wanted = [f"c{c}.H" for c in range(len(meta["wavelengths_m"]))]
            if meta["object_wave"]:
                wanted += [f"c{c}.O.{p}" for c in range(len(meta["wavelengths_m"]))
                           for p in ("re", "im")]
            missing = [n for n in wanted if n not in names]
            if missing:
                raise HologramFileError(f"{path}: missing channel(s) {', '.join(missing)}")
            pixels = {n: np.array(names[n].pixels, np.float32) for n in wanted}
    except HologramFileError:
        raise
    except Exception as e:  # the EXR library's errors: truncated or damaged data
        raise HologramFileError(f"{path}: unreadable EXR data ({e})") from e
    colours = range(len(meta["wavelengths_m"]))
    shape = tuple(meta["size_px"])
    for n, a in pixels.items():
        if a.shape != shape:
            raise HologramFileError(f"{path}: channel {n} is {a.shape}, metadata says {shape}")
    wave = None
    if meta["object_wave"]:
        wave = np.stack([pixels[f"c{c}.O.re"] + 1j * pixels[f"c{c}.O.im"] for c in colours])
        wave = wave.astype(np.complex64)
    ref = meta["reference"]
    return Hologram(intensity=np.stack([pixels[f"c{c}.H"] for c in colours]),
                    wavelengths=tuple(meta["wavelengths_m"]), pitch=meta["pitch_m"],
                    reference_angle=ref["angle_rad"], reference_azimuth=ref["azimuth_rad"],
                    reference_amplitudes=tuple(ref["amplitudes"]), object_wave=wave,
                    plate=np.array(meta["plate_to_world"], np.float64).reshape(4, 4),
                    bounds=np.array(meta["bounds_m"], np.float64),
                    band=meta.get("band_sin", 0.0), channels=tuple(meta.get("channels", ())),
                    point_density=meta.get("point_density_per_m2", 0.0))


def _check_exr(path: Path) -> None:
    if not path.is_file():
        raise HologramFileError(f"{path}: no such file")
    with open(path, "rb") as f:
        if f.read(4) != EXR_MAGIC:
            raise HologramFileError(f"{path}: not an OpenEXR file")


def _meta(path: Path, header) -> dict:
    if "holo" not in header:
        raise HologramFileError(f"{path}: an EXR image without hologram metadata; "
                                f"import it with import_acquired(pitch=, wavelength=, ...)")
    try:
        meta = json.loads(header["holo"])
    except (TypeError, ValueError) as e:
        raise HologramFileError(f"{path}: damaged hologram metadata ({e})") from e
    if meta.get("format") != FORMAT:
        raise HologramFileError(f"{path}: metadata format {meta.get('format')!r}, "
                                f"expected {FORMAT!r}")
    if meta.get("format_version") != FORMAT_VERSION:
        raise HologramFileError(f"{path}: format version {meta.get('format_version')!r} is "
                                f"not supported (this is holo {__version__}, which reads "
                                f"version {FORMAT_VERSION})")
    return meta


def import_acquired(path, *, pitch, wavelength, reference_angle=0.0, reference_azimuth=0.0):
    """An acquired (real) hologram from a grayscale PNG, TIFF or EXR image.

    ``pitch`` and ``wavelength`` [m], ``reference_angle`` ϑ and ``reference_azimuth`` φ [rad]
    describe the recording. Colour images are averaged to grey; integers scale to [0, 1].
    """
    pitch = validate.positive("pitch", pitch, "m")
    wavelength = validate.positive("wavelength", wavelength, "m")
    path = Path(path)
    if not path.is_file():
        raise HologramFileError(f"{path}: no such file")
    if path.suffix.lower() == ".exr":
        import OpenEXR
        _check_exr(path)
        with OpenEXR.File(str(path)) as f:
            chans = f.channels()
            grey = [n for n in ("Y", "R", "G", "B") if n in chans] or list(chans)[:1]
            image = np.mean([np.array(chans[n].pixels, np.float64) for n in grey], axis=0)
    else:
        from PIL import Image, UnidentifiedImageError
        try:
            with Image.open(path) as im:
                a = np.asarray(im)
        except (UnidentifiedImageError, OSError) as e:
            raise HologramFileError(f"{path}: not a readable PNG/TIFF image ({e})") from e
        scale = np.iinfo(a.dtype).max if np.issubdtype(a.dtype, np.integer) else 1.0
        image = a.astype(np.float64) / scale
        if image.ndim == 3:
            image = image[..., :3].mean(axis=2)
    return Hologram(intensity=image[None].astype(np.float32), wavelengths=(wavelength,),
                    pitch=pitch, reference_angle=float(reference_angle),
                    reference_azimuth=float(reference_azimuth), reference_amplitudes=(1.0,))
