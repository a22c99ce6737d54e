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


def show_image(path: Path, name: str):
    """The image file ``path`` as the image datablock ``name`` (loaded, or reloaded when it
    is there: the file changes frame by frame), shown in every open Image Editor."""
    image = bpy.data.images.get(name)
    if image is not None and bpy.path.abspath(image.filepath) != str(path):
        image.filepath = str(path)
    if image is None:
        image = bpy.data.images.load(str(path), check_existing=False)
        image.name = name
    image.reload()
    wm = getattr(bpy.context, "window_manager", None)
    for window in wm.windows if wm is not None else ():
        for area in window.screen.areas:
            if area.type == "IMAGE_EDITOR":
                area.spaces.active.image = image
                area.tag_redraw()
    return image
