"""Images as the scene shows them: a float EXR saved as a PNG through the scene's colour
management (its view transform, AgX by default, look, exposure and gamma), as Blender saves a
render."""

from __future__ import annotations

from pathlib import Path

import bpy

from . import compat


def save_as_displayed(scene, exr: Path, png: Path) -> Path:
    """``exr`` (its first layer: a pass's Combined, premultiplied RGBA) written to ``png`` as
    8-bit RGBA through ``scene``'s view transform; the scene's render output settings are
    left as they were."""
    image = bpy.data.images.load(str(exr), check_existing=False)
    try:
        with compat.png_output(scene):
            image.save_render(str(png), scene=scene)
    finally:
        bpy.data.images.remove(image)
    return png
