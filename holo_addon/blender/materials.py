"""Materials as the hologram sees them: the Principled BSDF's Base Color, its image, and the
inputs the emitters cannot show (lit by the scene: transparency; by their albedo: all but the
Base Color)."""

from __future__ import annotations

from . import compat

# Principled BSDF inputs that change a surface's look beyond its colour, and the value at
# which they do nothing. With the Albedo lighting none of them enters the hologram; lit by the
# scene (Cycles' radiance), all but transparency do: the emitters are opaque surfaces.
UNHONOURED = (
    ("Metallic", 0.0),
    ("Alpha", 1.0),
    ("Transmission Weight", 0.0),
    ("Emission Strength", 0.0),
    ("Coat Weight", 0.0),
    ("Sheen Weight", 0.0),
    ("Subsurface Weight", 0.0),
    ("Normal", None),
)
OPAQUE = ("Alpha", "Transmission Weight")


def unhonoured(material, *, lit=False) -> str | None:
    """A note naming what of ``material`` the holographic object does not show, or None;
    ``lit``: its colours are Cycles' radiance of the lit scene."""
    if material is None:
        return None
    node = principled(material)
    if node is None:
        return (
            None
            if lit
            else (
                f"material '{material.name}' has no Principled BSDF: the "
                f"holographic object uses its viewport colour"
            )
        )
    found = [
        name
        for name, off in UNHONOURED
        if name in node.inputs
        and (not lit or name in OPAQUE)
        and (
            node.inputs[name].is_linked
            or (off is not None and node.inputs[name].default_value != off)
        )
    ]
    if not found:
        return None
    if lit:
        return (
            f"material '{material.name}': {', '.join(found)} not shown by the holographic "
            f"object (its emitters are opaque surfaces)"
        )
    return (
        f"material '{material.name}': {', '.join(found)} not shown by the holographic "
        f"object (its emitters are diffuse: Base Color only; Lighting: Scene shows them)"
    )


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
