"""Objects in Blender's render: the ray visibility that keeps emitters out of the camera's view
of the raster (the holographic pass shows them) while they still cast shadows, light and show
in reflections, and keeps the plate out of it altogether."""

from __future__ import annotations

RAY_VISIBILITY = ("visible_camera", "visible_diffuse", "visible_glossy", "visible_transmission",
                  "visible_volume_scatter", "visible_shadow")
KEPT = "holo_ray_visibility"  # the user's own ray visibility, while the add-on sets it


def raster_visibility(obj) -> None:
    """An emitter is seen by the camera only through the holographic pass: hidden from camera
    rays alone, it still casts its shadow on raster objects, lights them indirectly and shows
    in their reflections and refractions (Object ▸ Visibility ▸ Ray Visibility; Cycles and
    EEVEE honour it, Workbench draws every object). The plate is a construction plane, hidden
    from every ray. The user's own ray visibility is kept on the object and restored when it
    is neither again. *Disable in Renders* stays the user's: it leaves the object out of the
    hologram too."""
    emitter, plate = obj.holo.emitter != "NONE", obj.holo.is_plate
    if not (emitter or plate):
        kept = obj.get(KEPT)
        if kept is not None:
            for name in RAY_VISIBILITY:
                setattr(obj, name, bool(kept.get(name, True)))
            del obj[KEPT]
        return
    if obj.get(KEPT) is None:
        obj[KEPT] = {name: bool(getattr(obj, name)) for name in RAY_VISIBILITY}
    for name in RAY_VISIBILITY:
        setattr(obj, name, not plate and name != "visible_camera")
