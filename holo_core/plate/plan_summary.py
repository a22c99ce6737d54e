"""A plate's plan in plain words, the verdict first (Plan Plate, the planner's command line):
whether its views are sharp, how long its first frame and a later view take on this
machine (:mod:`holo_core.estimate`), its samples, zone, wavelength, emitters, disk and memory.
Pure arithmetic, as the plan itself.
"""

from __future__ import annotations

from .. import estimate as estimate_mod
from .. import memory as memory_mod
from .plan import CHANNELS, PlatePlan, ViewPlan


def summary(
    p: PlatePlan,
    v: ViewPlan,
    *,
    lens: str,
    resolution,
    plate_size,
    camera,
    device=None,
    cache_dir=None,
    load_average=None,
) -> list[str]:
    """The plan in plain words, the verdict first: whether ``v``'s views (``resolution``
    (W, H) through ``lens``, e.g. '40 mm f/2.8', from ``camera`` (3,) [m]) are sharp, how
    long the first frame (the recording, its files and its view, in a new worker, the set-up
    said apart) and a later view take on this machine (:func:`holo_core.estimate.plate`, for
    ``device`` with the cache in ``cache_dir``, at ``load_average``, None: the machine's
    now), then the samples, the zone, the wavelength,
    the emitters, disk and memory (mm, µm, seconds, GiB)."""
    rows, cols = p.shape
    calibration = estimate_mod.load(device=device, cache_dir=cache_dir)
    first = estimate_mod.plate(
        p, v, device=device, cache_dir=cache_dir, calibration=calibration, load_average=load_average
    )
    later = estimate_mod.plate(
        p, v, record=False, calibration=calibration, warm=True, load_average=load_average
    )
    later_view = sum(s for name, s in later.work if name == "view")
    verdict = (
        "sharp"
        if v.sharp
        else f"blurred: they resolve {v.spot_px:.2g} px where a sharp "
        f"view resolves half a pixel; a longer lens, a wider aperture or Camera mode "
        f"makes them sharp"
    )
    lines = [
        f"verdict     views of {resolution[0]} x {resolution[1]} px through {lens} are {verdict}",
        f"time        the first frame (the plate recorded, its files written, its view) "
        f"{first.words()}; each later view about {estimate_mod.duration(later_view)} in the "
        f"same worker",
        f"plate       {p.size[0] * 1e3:.4g} x {p.size[1] * 1e3:.4g} mm of the {plate_size[0]:g} "
        f"x {plate_size[1]:g} m plate (where the objects' light reaches the zone): {cols} x "
        f"{rows} samples ({rows * cols / 1e6:.3g} Mpx), {p.pitch * 1e6:.3g} x "
        f"{p.row_pitch * 1e6:.3g} µm apart",
        f"zone        {p.zone.describe()}, for the camera at ({camera[0]:g}, {camera[1]:g}, "
        f"{camera[2]:g}) m",
        f"wavelength  {p.wavelength * 1e6:.4g} µm (the depth partner "
        f"{p.depth_wavelength * 1e6:.6g} µm): through {lens} a view resolves half a pixel",
        f"emitters    about {p.emitters:,}, one per resolved spot seen from the zone's centre",
        f"disk        {memory_mod.gib(p.disk_bytes())} for {p.looks} look(s) "
        f"({memory_mod.gib(p.disk_bytes(tiled=True))} recorded tile by tile); memory while "
        f"recording {memory_mod.gib(p.memory_bytes(CHANNELS * p.looks))} in one piece (the "
        f"looks together), {memory_mod.gib(p.memory_bytes(CHANNELS * p.looks, tiled=True))} "
        f"tile by tile",
        f"per view    reads {v.window / 1e6:.3g} Mpx of the plate for {p.looks} look(s)",
    ]
    if v.outside_zone > 0:
        lines.append(
            f"warning     the camera's pupil reaches {v.outside_zone * 1e3:.3g} mm "
            f"beyond the zone: its views will be cut off or soft"
        )
    return lines
