"""Objects in Blender's render: the ray visibility that keeps emitters and the plate out of the
raster."""

from __future__ import annotations

RAY_VISIBILITY = ("visible_camera", "visible_diffuse", "visible_glossy", "visible_transmission",
                  "visible_volume_scatter", "visible_shadow")


def raster_visibility(obj) -> None:
    """A holographic emitter or the plate appears only through the holographic pass: it stays
    in the render (so the render's depsgraph evaluates it at render settings) but is hidden
    from the camera and every ray (Object ▸ Visibility ▸ Ray Visibility; Cycles and EEVEE honour
    it, Workbench draws every object). *Disable in Renders* stays the user's: it leaves the
    object out of the hologram too."""
    shown = obj.holo.emitter == "NONE" and not obj.holo.is_plate
    for name in RAY_VISIBILITY:
        setattr(obj, name, shown)
