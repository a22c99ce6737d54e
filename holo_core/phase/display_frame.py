"""One frame of a holographic display's animation, from the recorded waves to the files its
SLM driver takes, and what the display will show.

A :class:`DisplayFrame` names, per laser, the plate recorded for it (the scene's wave, its
lengths in the scene's metres: ``scale`` display metres per scene metre turns them into
the display's) and the display's description. :func:`make_frame` carries each laser's wave
to the display's grid (back from the volume's front where the wave was recorded there),
encodes it, quantises it to the display's codes and simulates the focal stack the quantised
pattern shows against the unencoded wave's (PSNR and SSIM per slice), then writes every file
of the frame at once (:func:`holo_core.io.image.atomic_paths`): the patterns, the focal
stack (EXR) and its contact sheet (PNG), and last the layout (JSON) that names them. A
frame's files appear together or not at all; a failed or cancelled frame leaves the earlier
frames as they were.

Run as ``python -m holo_core.phase.display_frame FOLDER``: reads ``FOLDER/frame.json``,
prints ``HOLO_PROGRESS <fraction>`` lines and the result's JSON as its last line. It loads
the OpenCL driver where its stages do; Blender's process only starts it.
"""

from __future__ import annotations

import json
import logging
import math
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np

from .. import jobs, validate
from ..io.image import atomic_paths, png_bytes, srgb, write_exr
from ..optics.metrics import psnr, ssim
from ..validate import InputError
from .display import Display, display_field
from .encoding import double_phase

log = logging.getLogger(__name__)
FORMATS = {"PNG8": 8, "PNG16": 16, "PACKED10": 10}
METHODS = ("double-phase",)
LAYOUT_VERSION = 1


@dataclass(frozen=True, slots=True, kw_only=True)
class FrameLaser:
    """One laser of the frame: ``name``, ``wavelength`` [m], ``power`` [W], the plate
    ``hologram`` recorded for it [path] and the ``channel`` of it that holds its colour."""

    name: str
    wavelength: float
    power: float
    hologram: str
    channel: int

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise InputError(f"laser name must be a word (red, green, blue); got {self.name!r}"
                             [:200])
        validate.length("laser wavelength", self.wavelength)
        if not (math.isfinite(self.power) and self.power >= 0):
            raise InputError(f"laser power must be >= 0 [W]; got {self.power!r}")
        validate.integer("laser channel", self.channel, 0, 3)


@dataclass(frozen=True, slots=True, kw_only=True)
class DisplayFrame:
    """Frame ``frame`` of display ``name``, written into ``folder``.

    resolution, pitch [m], bit_depth, phase_range [rad], inverted : the display
    pattern_format : 'PNG8' (8-bit grey), 'PNG16' (16-bit grey) or 'PACKED10' (10 bits, the
        8 high in red and the 2 low in blue of an 8-bit RGB PNG)
    lasers : (:class:`FrameLaser`, ...)
    scale : display metres per scene metre (the recorded waves' lengths times it)
    front : [m] the plane in front of the display the waves were recorded on (0: the display)
    distance : [m] the scene's mean signed depth (negative: behind), for the layout
    method : the encoding
    depths : [m] the focal stack's slices, signed depths off the display
    digest : of what the frame is made from (written into the layout)
    """

    name: str
    frame: int
    folder: str
    resolution: tuple
    pitch: float
    bit_depth: int
    phase_range: float
    inverted: bool
    pattern_format: str
    lasers: tuple
    scale: float
    front: float
    distance: float
    method: str
    depths: tuple
    digest: str = ""

    def __post_init__(self):
        object.__setattr__(self, "lasers", tuple(
            laser if isinstance(laser, FrameLaser) else FrameLaser(**laser)
            for laser in self.lasers))
        if not self.lasers:
            raise InputError("lasers must name at least one laser")
        validate.choice("pattern_format", self.pattern_format, tuple(FORMATS))
        if FORMATS[self.pattern_format] < self.bit_depth:
            raise InputError(f"pattern_format {self.pattern_format} holds "
                             f"{FORMATS[self.pattern_format]} bits, fewer than bit_depth "
                             f"{self.bit_depth}")
        validate.choice("method", self.method, METHODS)
        validate.integer("frame", self.frame, 0, 1048574)
        if not (self.scale > 0 and math.isfinite(self.scale)):
            raise InputError(f"scale must be > 0 (display metres per scene metre); got "
                             f"{self.scale!r}")
        object.__setattr__(self, "resolution", tuple(int(v) for v in self.resolution))
        object.__setattr__(self, "depths", tuple(float(z) for z in self.depths))
        if not self.depths:
            raise InputError("depths must hold at least one slice")

    @property
    def display(self) -> Display:
        return Display(name=self.name[:100] or "display", resolution=self.resolution,
                       pitch=self.pitch, bit_depth=self.bit_depth)

    def stem(self) -> str:
        return f"frame_{self.frame:04d}"

    def to_dict(self) -> dict:
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d["lasers"] = [asdict(laser) for laser in self.lasers]
        return d

    @classmethod
    def from_dict(cls, data) -> DisplayFrame:
        if not isinstance(data, dict):
            raise InputError("a display frame must be a dict of its fields")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise InputError(f"display frame has no field {', '.join(unknown)}")
        return cls(**data)

    def paths(self) -> dict:
        """Every file of the frame: per laser its pattern, then the stack and its sheet, and
        the layout last (it names the others: written last, it appears with them)."""
        folder, stem = Path(self.folder), self.stem()
        out = {laser.name: folder / f"{stem}_{laser.name}.png" for laser in self.lasers}
        out["stack"] = folder / f"{stem}_stack.exr"
        out["sheet"] = folder / f"{stem}_stack.png"
        out["layout"] = folder / f"{stem}.json"
        return out


def codes_of(phase: np.ndarray, *, bit_depth: int, phase_range: float,
             inverted: bool) -> np.ndarray:
    """The SLM's codes (uint16) for ``phase`` [rad]: code k shows k·phase_range/2^bits
    (−k·… when ``inverted``); each phase is taken modulo 2π into the codes' range, to the
    nearest level. Never outside [0, 2^bits)."""
    levels = 1 << bit_depth
    step = phase_range / levels
    wrapped = np.remainder(-phase if inverted else phase, 2 * math.pi)
    codes = np.round(wrapped / step).astype(np.int64)
    codes[codes * step >= 2 * math.pi - step / 2] %= max(1, round(2 * math.pi / step))
    codes = np.clip(codes, 0, levels - 1)
    return codes.astype(np.uint16)


def shown_phase(codes: np.ndarray, *, bit_depth: int, phase_range: float,
                inverted: bool) -> np.ndarray:
    """The phase [rad] the SLM shows for ``codes``."""
    phase = codes.astype(np.float64) * (phase_range / (1 << bit_depth))
    return -phase if inverted else phase


def pattern_png(codes: np.ndarray, fmt: str) -> bytes:
    """The pattern file as the driver takes it: an 8-bit or 16-bit grey PNG, or 10 bits
    packed in an 8-bit RGB PNG (the 8 high bits in red, the 2 low in blue's high bits)."""
    if fmt == "PNG8":
        return png_bytes(codes.astype(np.float64) / 255)
    if fmt == "PACKED10":
        rgb = np.zeros(codes.shape + (3,), np.float64)
        rgb[..., 0] = (codes >> 2) / 255
        rgb[..., 2] = ((codes & 3) << 6) / 255
        return png_bytes(rgb)
    return _png16(codes)


def _png16(codes: np.ndarray) -> bytes:
    import struct
    import zlib
    h, w = codes.shape
    rows = codes.astype(">u2").reshape(h, -1).view(np.uint8)
    raw = np.concatenate([np.zeros((h, 1), np.uint8), rows], axis=1).tobytes()

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(
            ">I", zlib.crc32(kind + body) & 0xFFFFFFFF)
    header = struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 6)) \
        + chunk(b"IEND", b"")


def wave_at_display(frame: DisplayFrame, laser: FrameLaser) -> np.ndarray:
    """The laser's wave on the display's grid (rows, cols), complex128, its largest
    amplitude 1: the recorded plate resampled to pitch / scale (its lengths are the scene's),
    carried back from the volume's front by the angular spectrum where it was recorded
    there."""
    from ..io.plate_paths import read_plate
    hologram = read_plate(Path(laser.hologram))
    s, p = frame.scale, frame.pitch
    cols, rows = frame.resolution
    pad = 0
    if frame.front > 0:  # the light the display's edge sends to the eye box crosses the front
        sin_t = min(laser.wavelength / (2 * p), 0.99)
        pad = math.ceil(frame.front * sin_t / math.sqrt(1 - sin_t**2) / p) + 8
    wide = Display(name=frame.display.name, resolution=(cols + 2 * pad, rows + 2 * pad),
                   pitch=p / s)
    u = np.asarray(display_field(hologram, wide, channel=laser.channel), np.complex128)
    if frame.front > 0:
        u = _propagate(u, laser.wavelength, p, -frame.front)[pad:pad + rows, pad:pad + cols]
    peak = float(np.abs(u).max())
    if not peak > 0 or not np.isfinite(u).all():
        raise InputError(f"the recorded wave of the {laser.name} laser ({laser.hologram}) is "
                         f"zero or not finite on the display: nothing to encode")
    return u / peak


def _propagate(u: np.ndarray, wavelength: float, pitch: float, distance: float) -> np.ndarray:
    """The angular spectrum of ``u`` over ``distance`` [m], float64 NumPy, padded twice,
    evanescent waves dropped (a focal stack's reference: the same arithmetic for the
    encoded and the unencoded wave)."""
    if distance == 0:
        return u.copy()
    rows, cols = u.shape
    padded = np.zeros((2 * rows, 2 * cols), np.complex128)
    padded[rows // 2:rows // 2 + rows, cols // 2:cols // 2 + cols] = u
    fy = np.fft.fftfreq(2 * rows, pitch)[:, None]
    fx = np.fft.fftfreq(2 * cols, pitch)[None, :]
    arg = 1 / wavelength**2 - fx**2 - fy**2
    kz = 2 * math.pi * np.sqrt(np.maximum(arg, 0))
    h = np.where(arg > 0, np.exp(1j * kz * distance), 0)
    out = np.fft.ifft2(np.fft.fft2(padded) * h)
    return out[rows // 2:rows // 2 + rows, cols // 2:cols // 2 + cols]


def _filtered(u: np.ndarray, pitch: float) -> np.ndarray:
    """``u`` through the display's 4f filter: frequencies below half its Nyquist frequency
    kept per axis (what double-phase's checkerboard needs cut)."""
    rows, cols = u.shape
    keep = (np.abs(np.fft.fftfreq(rows, pitch))[:, None] < 1 / (4 * pitch)) & \
        (np.abs(np.fft.fftfreq(cols, pitch))[None, :] < 1 / (4 * pitch))
    return np.fft.ifft2(np.fft.fft2(u) * keep)


def focal_stack(field: np.ndarray, wavelength: float, pitch: float, depths) -> np.ndarray:
    """Intensities (slices, rows, cols) float64 of ``field`` on the display, through its 4f
    filter, at each of ``depths`` [m] (signed: negative behind the display)."""
    u = _filtered(field, pitch)
    return np.stack([np.abs(_propagate(u, wavelength, pitch, z))**2 for z in depths])


def make_frame(frame: DisplayFrame, progress: jobs.Progress = None) -> dict:
    """Make and write the frame (module docstring); returns its layout (a dict, as the JSON
    file holds it), with each laser's PSNR [dB] and SSIM per slice."""
    started = time.perf_counter()
    paths = frame.paths()
    Path(frame.folder).mkdir(parents=True, exist_ok=True)
    files, lasers = {}, []
    n = len(frame.lasers)
    shown_stack, reference_stack = {}, {}
    for i, laser in enumerate(frame.lasers):
        jobs.report(progress, i, n)
        u = wave_at_display(frame, laser)
        phase = double_phase(u)
        codes = codes_of(phase, bit_depth=frame.bit_depth, phase_range=frame.phase_range,
                         inverted=frame.inverted)
        if int(codes.max()) >= 1 << frame.bit_depth:
            raise InputError(f"the {laser.name} pattern holds codes beyond "
                             f"{frame.bit_depth} bits")
        files[laser.name] = pattern_png(codes, frame.pattern_format)
        shown = np.exp(1j * shown_phase(codes, bit_depth=frame.bit_depth,
                                        phase_range=frame.phase_range,
                                        inverted=frame.inverted))
        if frame.inverted:  # the SLM's phase is the pattern's, reversed: conjugate back
            shown = np.conj(shown)
        jobs.report(progress, i + 0.5, n)
        got = focal_stack(shown, laser.wavelength, frame.pitch, frame.depths)
        ref = focal_stack(u, laser.wavelength, frame.pitch, frame.depths)
        # the pattern's light is spread over the checkerboard's orders: compared at the
        # reference's energy in each slice (the least-squares gain)
        gains = np.einsum("kij,kij->k", got, ref) / np.maximum(
            np.einsum("kij,kij->k", got, got), 1e-300)
        got = got * gains[:, None, None]
        peak = float(ref.max())
        scores = [(psnr(g, r, data_range=peak), ssim(g, r, data_range=peak))
                  for g, r in zip(got, ref)]
        shown_stack[laser], reference_stack[laser] = got, ref
        lasers.append({"name": laser.name, "wavelength": laser.wavelength,
                       "power": laser.power, "pattern": paths[laser.name].name,
                       "format": frame.pattern_format, "bit_depth": frame.bit_depth,
                       "phase_range": frame.phase_range, "inverted": frame.inverted,
                       "encoding": frame.method, "table": None,
                       "psnr_db": [round(float(a), 3) for a, _ in scores],
                       "ssim": [round(float(b), 4) for _, b in scores]})
    channels, sheet = _stack_images(frame, shown_stack, reference_stack)
    layout = {"version": LAYOUT_VERSION, "display": frame.name, "frame": frame.frame,
              "resolution": list(frame.resolution), "pitch": frame.pitch,
              "distance": frame.distance, "scale": frame.scale, "digest": frame.digest,
              "lasers": lasers,
              "stack": {"file": paths["stack"].name, "sheet": paths["sheet"].name,
                        "depths": list(frame.depths),
                        "rows": "each slice's row: the pattern's above, the wave's below"}}
    stack = _exr_bytes(channels, holo=json.dumps({"display": frame.name, "frame": frame.frame,
                                                  "depths": list(frame.depths)}))
    with atomic_paths(*(paths[laser.name] for laser in frame.lasers), paths["stack"],
                      paths["sheet"], paths["layout"]) as temps:
        for laser, tmp in zip(frame.lasers, temps):
            Path(tmp).write_bytes(files[laser.name])
        Path(temps[n]).write_bytes(stack)
        Path(temps[n + 1]).write_bytes(png_bytes(sheet))
        Path(temps[n + 2]).write_text(json.dumps(layout, indent=1) + "\n")
    jobs.report(progress, 1, 1)
    log.info("display frame %d: %d pattern(s) in %.1f s", frame.frame, n,
             time.perf_counter() - started)
    return layout


def _exr_bytes(channels: dict, **header) -> bytes:
    """The OpenEXR file of ``channels`` as bytes (written in a scratch folder: the frame's
    files are renamed into place together, under one lock)."""
    with tempfile.TemporaryDirectory(prefix="holo-stack-") as folder:
        path = Path(folder) / "stack.exr"
        write_exr(path, channels, **header)
        return path.read_bytes()


def _stack_images(frame: DisplayFrame, shown: dict, reference: dict):
    """(the EXR's channels: slice k's colour c as ``shown.k.C`` and ``wave.k.C``, float32; the
    contact sheet: the slices side by side, the pattern's above the wave's, each laser in
    its colour weighted by its power, sRGB in [0, 1])."""
    names = "RGB"
    slices = len(frame.depths)
    rows, cols = next(iter(shown.values())).shape[1:]
    channels = {}
    mixed = {kind: np.zeros((slices, rows, cols, 3)) for kind in ("shown", "wave")}
    powers = [laser.power for laser in shown] or [1.0]
    top = max(powers) or 1.0
    for laser in shown:
        for kind, stack in (("shown", shown[laser]), ("wave", reference[laser])):
            for k in range(slices):
                channels[f"{kind}.{k:02d}.{names[laser.channel]}"] = stack[k].astype(np.float32)
            mixed[kind][..., laser.channel] += stack * (laser.power / top if top else 1.0)
    white = float(np.percentile(mixed["wave"], 99.9)) or 1.0
    sheet = np.concatenate([np.concatenate(list(mixed[kind]), axis=1)
                            for kind in ("shown", "wave")], axis=0)
    return channels, srgb(np.clip(sheet / white, 0, 1))


def main(argv=None) -> int:
    """``python -m holo_core.phase.display_frame FOLDER``: the frame of ``FOLDER/frame.json``
    made; progress lines on stdout, the layout's JSON as the last line; status 1 and the
    reason on stderr when it fails."""
    argv = sys.argv[1:] if argv is None else argv
    logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(message)s")
    if len(argv) != 1:
        print("usage: python -m holo_core.phase.display_frame FOLDER", file=sys.stderr)
        return 2
    try:
        frame = DisplayFrame.from_dict(json.loads((Path(argv[0]) / "frame.json").read_text()))
        layout = make_frame(frame, lambda f: print(f"HOLO_PROGRESS {f:.4f}", flush=True))
    except (ValueError, OSError) as e:
        print(f"{type(e).__name__}: {e}", file=sys.stderr)
        return 1
    print(json.dumps(layout), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
