"""Holo for Blender: holographic objects recorded, rendered by wave optics and composited in
depth with the rasterized scene.

Files: ``properties`` (Object.holo, Scene.holo), ``scene_export`` (scene → metres, as the
render sees it), ``bake`` (procedural Base Colours baked by Cycles), ``pipeline`` (record and
render in a worker process), ``preferences`` (device, memory, cache, CPU runtime),
``operators``, ``compositing`` (Depth Combine and the per-frame pass), ``overlay`` (the
plate's coverage in the viewport), ``compat`` (Blender 4.x/5.x), ``ui`` (panels), ``demo``
(the built-in scene).
"""

from . import compositing, operators, overlay, preferences, properties, ui

MODULES = (properties, preferences, operators, ui, compositing, overlay)


def register():
    for m in MODULES:
        m.register()


def unregister():
    for m in reversed(MODULES):
        m.unregister()
