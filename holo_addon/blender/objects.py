"""Objects in Blender's render: an emitter is a holdout in the raster (the holographic pass
fills its hole, so Cycles' depth of field and motion blur decide what covers what) while it
still casts shadows, lights and shows in reflections; the plate is out of the raster."""

from __future__ import annotations

from contextlib import contextmanager

import bpy

RAY_VISIBILITY = (
    "visible_camera",
    "visible_diffuse",
    "visible_glossy",
    "visible_transmission",
    "visible_volume_scatter",
    "visible_shadow",
)
HOLDOUT = "is_holdout"
KEPT = "holo_ray_visibility"  # the user's own ray visibility, while the add-on sets it


def raster_visibility(obj) -> None:
    """An emitter is a holdout in the raster (Object ▸ Visibility ▸ Holdout): the camera sees
    a hole where it is the nearest surface, cut by Cycles' (or EEVEE's) own depth of field and
    motion blur, which the holographic pass fills (:mod:`holo_addon.compositor.tree`); it
    still casts its shadow on raster objects, lights them indirectly and shows in their
    reflections and refractions (a holdout is one for camera rays alone). The plate is a
    construction plane, hidden from every ray; an imported plate (File ▸ Import ▸ Hologram)
    is the window its recorded objects are seen through, so it is a holdout for camera rays
    alone, the hole the pass fills. The user's own visibility is kept on the object and
    restored when it is neither again. *Disable in Renders* stays the user's: it leaves the
    object out of the hologram too. A holographic display's plane is a construction plane,
    as a plate is."""
    emitter = obj.holo.emitter != "NONE"
    plate = obj.holo.is_plate or obj.holo.is_display
    window = plate and obj.holo.imported
    if not (emitter or plate):
        kept = obj.get(KEPT)
        if kept is not None:
            for name in (*RAY_VISIBILITY, HOLDOUT):
                setattr(obj, name, bool(kept.get(name, name != HOLDOUT)))
            del obj[KEPT]
        return
    if obj.get(KEPT) is None:
        obj[KEPT] = {name: bool(getattr(obj, name)) for name in (*RAY_VISIBILITY, HOLDOUT)}
    for name in RAY_VISIBILITY:
        setattr(obj, name, not plate or (window and name == "visible_camera"))
    setattr(obj, HOLDOUT, not plate or window)


def show_as_raster(obj) -> None:
    """``obj`` an ordinary object of the raster: seen by every ray, no holdout."""
    for name in RAY_VISIBILITY:
        setattr(obj, name, True)
    setattr(obj, HOLDOUT, False)


@contextmanager
def seen_by_every_ray(obj):
    """``obj`` as an ordinary object (:func:`show_as_raster`) for a while, as a bake needs
    it."""
    kept = {name: getattr(obj, name) for name in (*RAY_VISIBILITY, HOLDOUT)}
    try:
        show_as_raster(obj)
        yield obj
    finally:
        for name, value in kept.items():
            setattr(obj, name, value)


@contextmanager
def shown_as_rendered(scene, view_layer=None):
    """Emitters that the render draws but the viewport hides (H, Disable in Viewports, or a
    collection hidden in the viewport) shown while the viewport's depsgraph is evaluated, as
    Blender's render draws them; restored afterwards. Yields whether anything was shown."""
    view_layer = view_layer or bpy.context.view_layer
    objects, collections = [], []
    for obj in scene.objects:
        if obj.type != "MESH" or obj.holo.emitter == "NONE" or obj.holo.is_plate or obj.hide_render:
            continue
        try:
            hidden = obj.hide_get(view_layer=view_layer)
        except RuntimeError:  # not in this view layer (an excluded collection): not rendered
            continue
        if hidden or obj.hide_viewport:
            objects.append((obj, hidden, obj.hide_viewport))
        for lc in _layer_collections(view_layer.layer_collection, obj.users_collection):
            if lc.hide_viewport or lc.collection.hide_viewport:
                collections.append((lc, lc.hide_viewport, lc.collection.hide_viewport))
    for lc, _, _ in collections:
        lc.hide_viewport = lc.collection.hide_viewport = False
    for obj, _, _ in objects:
        obj.hide_viewport = False
        obj.hide_set(False, view_layer=view_layer)
    try:
        yield bool(objects or collections)
    finally:
        for obj, hidden, viewport in objects:
            obj.hide_viewport = viewport
            obj.hide_set(hidden, view_layer=view_layer)
        for lc, hidden, viewport in reversed(collections):
            lc.hide_viewport, lc.collection.hide_viewport = hidden, viewport


def _layer_collections(root, collections):
    """The layer collections on the way from ``root`` to each of ``collections``."""
    wanted = {c.as_pointer() for c in collections}
    found = []

    def walk(lc, path):
        path = path + [lc]
        if lc.collection.as_pointer() in wanted:
            found.extend(p for p in path if p not in found)
        for child in lc.children:
            walk(child, path)

    walk(root, [])
    return found
