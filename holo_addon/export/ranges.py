"""Settings read from a .blend checked against their own properties' ranges before any work.

The panel clamps what a user types, but a script that sets the stored value (``scene.holo[
"iterations"] = 10**9``), a file of another version or a damaged one hands the add-on numbers
outside them (an Iterations of 10⁹ would ask for 10 GB before anything refused it). The ranges
are the properties' own (``min``/``max`` in :mod:`holo_addon.ui.properties`), read from
Blender's description of them, so they are written once; a setting outside is named as the
panel names it, with the panel's units.
"""

from __future__ import annotations

import math
import re

import bpy

from .scene import ExportError

WHERE = {
    "HoloSceneSettings": "Render Properties ▸ Holo",
    "HoloObjectSettings": "Object Properties ▸ Holo",
}
_UNIT = re.compile(r"\[([^\]]+)\]")  # a description's unit: "… in memory [GiB]: …"


def check(settings, scene) -> None:
    """:class:`ExportError` naming the first setting of ``settings`` (``Scene.holo`` or
    ``Object.holo``) outside its property's range, not a finite number, or not one of its
    choices, with the range and the value in the panel's units (``scene``: its unit
    system, for lengths)."""
    rna = settings.bl_rna
    where = WHERE.get(rna.identifier, rna.name)
    owner = getattr(settings.id_data, "name", "")
    if isinstance(settings.id_data, bpy.types.Object):
        where = f"{where}, object '{owner}'"
    for prop in rna.properties:
        if prop.identifier == "rna_type":
            continue
        if prop.type in ("INT", "FLOAT"):
            value = getattr(settings, prop.identifier)
            for v in tuple(value) if prop.is_array else (value,):
                if not (math.isfinite(v) and prop.hard_min <= v <= prop.hard_max):
                    raise ExportError(
                        f"{prop.name} ({where}) must be "
                        f"{_range(prop, scene)}; got {_shown(prop, v, scene)}"
                    )
        elif prop.type == "ENUM" and not prop.is_enum_flag:
            stored = settings.get(prop.identifier)  # the file's number (None: the default)
            if stored is not None and stored not in {item.value for item in prop.enum_items}:
                items = ", ".join(item.name for item in prop.enum_items)
                raise ExportError(
                    f"{prop.name} ({where}) must be one of {items}; the file "
                    f"holds none of them ({stored!r})"
                )


def _range(prop, scene) -> str:
    """The range a property takes, as the panel shows it: "within 1 … 64", "at least 0.1
    GiB"."""
    low, high = prop.hard_min, prop.hard_max
    unbounded = 2**31 - 1 if prop.type == "INT" else 1e30
    if high >= unbounded:
        return f"at least {_shown(prop, low, scene)}"
    if low <= -unbounded:
        return f"at most {_shown(prop, high, scene)}"
    return f"within {_shown(prop, low, scene)} … {_shown(prop, high, scene)}"


def _shown(prop, value, scene) -> str:
    """``value`` of ``prop`` in the panel's units: lengths in the scene's unit system, a
    unit the description names in brackets after the number."""
    if prop.type == "INT":
        return str(value)
    if not math.isfinite(value):
        return str(value)
    if prop.unit == "LENGTH" and scene is not None:
        return _length(value, scene.unit_settings)
    unit = _UNIT.search(prop.description)
    return f"{value:.6g}" + (f" {unit.group(1)}" if unit else "")


LENGTH_UNITS = {
    "KILOMETERS": "km",
    "METERS": "m",
    "CENTIMETERS": "cm",
    "MILLIMETERS": "mm",
    "MICROMETERS": "um",
    "MILES": "mi",
    "FEET": "ft",
    "INCHES": "in",
    "THOU": "thou",
}


def _length(value: float, units) -> str:
    """A length in Blender units as the panel shows it: in the scene's Length unit (Unit
    Scale applied), Blender's own choice where it is Adaptive."""
    metres = value * units.scale_length
    symbol = LENGTH_UNITS.get(units.length_unit) if units.system != "NONE" else None
    if symbol is None:
        return bpy.utils.units.to_string(units.system, "LENGTH", metres, precision=6)
    per = bpy.utils.units.to_value(units.system, "LENGTH", f"1{symbol}")
    return f"{metres / per:.6g} {symbol.replace('um', 'µm')}"
