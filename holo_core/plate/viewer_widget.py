"""A notebook widget over a :class:`~holo_core.plate.viewer.PlateViewer`: sliders move the
camera (across, up, along its view [m]; its aim [°]) and its focus [m], and the picture follows
(coarse while a slider moves; its button draws the full view). ipywidgets is optional:
without it, :func:`widget` says how to install it."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..io.image import png_bytes, srgb
from ..scene.camera import Camera
from ..validate import InputError

MOVE = 0.05  # [m] the position sliders' reach either way, at most ...
TURN = 10.0  # [°] ... and the aim sliders'


def moved(
    camera: Camera, *, across=0.0, up=0.0, along=0.0, yaw=0.0, pitch=0.0, focus=None
) -> Camera:
    """``camera`` moved ``across``, ``up`` and ``along`` [m] its own axes (x right, y up, z
    back), turned by ``yaw`` about its up axis and ``pitch`` about its right axis [°], and
    focused at ``focus`` [m] (None: as it was)."""
    m = np.array(camera.matrix_world, np.float64)
    r = camera.rotation
    m[:3, 3] += r @ np.array([across, up, along])
    a, b = math.radians(yaw), math.radians(pitch)
    turn_y = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    turn_x = np.array([[1, 0, 0], [0, math.cos(b), -math.sin(b)], [0, math.sin(b), math.cos(b)]])
    m[:3, :3] = m[:3, :3] @ turn_y @ turn_x
    lens = {} if focus is None or camera.fstop is None else {"focus_distance": float(focus)}
    return replace(camera, matrix_world=m, **lens)


def picture(view) -> bytes:
    """A view's radiance over black, sRGB, as PNG bytes."""
    return png_bytes(srgb(view.rgb * view.alpha[..., None]))


def widget(viewer, camera: Camera, *, coarse: bool = True):
    """The sliders and the picture of :meth:`PlateViewer.widget`."""
    try:
        import ipywidgets
    except ImportError:
        raise InputError(
            "PlateViewer.widget needs ipywidgets (pip install ipywidgets); "
            "PlateViewer.view gives the views without it"
        ) from None
    if not isinstance(camera, Camera):
        raise InputError(f"camera must be a Camera; got {type(camera).__name__}")
    reach = min(MOVE, _zone_reach(viewer, camera))

    def slider(name, lo, hi, value=0.0, step=None):
        return ipywidgets.FloatSlider(
            value=value,
            min=lo,
            max=hi,
            step=step or (hi - lo) / 200,
            description=name,
            continuous_update=coarse,
        )

    sliders = {
        "across": slider("across [m]", -reach, reach),
        "up": slider("up [m]", -reach, reach),
        "along": slider("along [m]", -reach, reach),
        "yaw": slider("aim ← → [°]", -TURN, TURN),
        "pitch": slider("aim ↓ ↑ [°]", -TURN, TURN),
    }
    if camera.fstop is not None:
        f = camera.focus_distance
        sliders["focus"] = slider("focus [m]", 0.5 * f, 2 * f, f)
    image = ipywidgets.Image(format="png")
    words = ipywidgets.Label()
    full = ipywidgets.Button(description="full view")

    def draw(quick: bool):
        cam = moved(camera, **{k: s.value for k, s in sliders.items()})
        why = viewer.where(cam)
        if why is not None:  # said, and no stale picture left as if it were this camera's
            words.value = why
            image.value = b""
            return
        words.value = "coarse: the full view with the button" if quick else ""
        image.value = picture(viewer.view(cam, coarse=quick))

    for s in sliders.values():
        s.observe(lambda change: draw(coarse), names="value")
    full.on_click(lambda button: draw(False))
    draw(False)
    return ipywidgets.VBox([*sliders.values(), full, words, image])


def _zone_reach(viewer, camera: Camera) -> float:
    """[m] the zone's smallest half extent, the sliders' reach (a pupil beyond it is said)."""
    held = viewer._source.current()
    holos = getattr(held, "holos", None)
    zone = holos[0].zone if holos else None
    if zone is None:
        return MOVE
    return float(min(zone.half_extents))
