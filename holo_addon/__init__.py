"""Holo for Blender: holographic objects recorded, rendered by wave optics and composited in
depth with the rasterized scene. Shaped as the glTF add-on, each folder importing only those
below it (ui → compositor → render → export → blender):

- ``blender/``: Blender helpers shared by the rest (4.x/5.x ``compat``, ``materials``, ``objects``)
- ``export/``: the scene as the render sees it → holo_core's nouns in metres (``scene``), the
  plate checked against the camera's view (``plates``), the whole typed job read in one visit
  with its digests (``job``), the holographic display and its per-laser plate jobs
  (``display``), the emitters across the shutter (``motion``), what Cycles needs
  to render the emitters' lit radiance and its digest (``radiance``), and procedural Base
  Colours baked by Cycles (``bake``, Lighting: Albedo)
- ``render/``: the job made in a worker process or its pass reused (``pipeline``), a
  display's frame (``display``: its waves recorded, then the core's frame stage), with the
  preferences' ``options``; the Cycles script that renders the emitters' radiance
  (``cycles_radiance``)
- ``compositor/``: the render's life: the pass in the compositor's ``tree`` (the emitters'
  holdouts filled by the pass), the frame ``handlers`` (a pass per rendered frame) and the
  ``session`` (runtime state the panels read)
- ``ui/``: ``properties`` (Object.holo, Scene.holo), ``preferences``, ``operators``, ``plates``
  (the viewing zone, the planner, File ▸ Import ▸ Hologram), ``display`` (the holographic
  display's panel and Export Display Frame), ``panels``, the plate's
  coverage and viewing zone ``overlay`` in the viewport, and the holographic ``preview`` in
  the camera's view
- ``demo`` (the built-in scene), ``display_demo`` (an animation on a holographic display) and
  ``build`` (the extension's zip), run as modules
"""

from .compositor import handlers
from .ui import (
    display,
    live,
    operators,
    overlay,
    panels,
    plates,
    preferences,
    preview,
    properties,
)

MODULES = (
    properties,
    preferences,
    operators,
    plates,
    display,
    panels,
    handlers,
    overlay,
    preview,
    live,
)


def register():
    for m in MODULES:
        m.register()


def unregister():
    for m in reversed(MODULES):
        m.unregister()
