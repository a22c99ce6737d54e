"""Materials as the hologram sees them: the Principled BSDF's Base Color, its image, and the
inputs a diffuse emitter cannot show."""

from __future__ import annotations

from . import compat

# Principled BSDF inputs that change a surface's look beyond its colour, and the value at
# which they do nothing. Emitters are diffuse: none of them enters the hologram.
UNHONOURED = (("Metallic", 0.0), ("Alpha", 1.0), ("Transmission Weight", 0.0),
              ("Emission Strength", 0.0), ("Coat Weight", 0.0), ("Sheen Weight", 0.0),
              ("Subsurface Weight", 0.0), ("Normal", None))


def unhonoured(material) -> str | None:
    """A note naming what of ``material`` the holographic object does not show, or None."""
    if material is None:
        return None
    node = principled(material)
    if node is None:
        return (f"material '{material.name}' has no Principled BSDF: the holographic object "
                f"uses its viewport colour")
    found = [name for name, off in UNHONOURED if name in node.inputs and (
        node.inputs[name].is_linked or
        off is not None and node.inputs[name].default_value != off)]
    if not found:
        return None
    return (f"material '{material.name}': {', '.join(found)} not shown by the holographic "
            f"object (its emitters are diffuse: Base Color only)")


def principled(material):
    if material is None or material.node_tree is None or not compat.uses_nodes(material):
        return None
    return next((n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)


def base_colour(material) -> tuple:
    if material is None:
        return (1.0, 1.0, 1.0)
    node = principled(material)
    if node is not None:
        return tuple(node.inputs["Base Color"].default_value[:3])
    return tuple(material.diffuse_color[:3])


