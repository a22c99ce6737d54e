"""Holo for Blender: holographic objects recorded, rendered by wave optics and composited in
depth with the rasterized scene.

Files: ``properties`` (Object.holo, Scene.holo), ``scene_export`` (scene → metres),
``pipeline`` (record and render off the main thread), ``operators``, ``compositing``
(Depth Combine and the per-frame pass), ``compat`` (Blender 4.x/5.x), ``ui`` (panels),
``demo`` (the built-in scene).
"""

from . import compositing, operators, properties, ui

MODULES = (properties, operators, ui, compositing)


def register():
    for m in MODULES:
        m.register()


def unregister():
    for m in reversed(MODULES):
        m.unregister()
