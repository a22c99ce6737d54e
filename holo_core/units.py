"""Lengths with their units, as people type them, to metres; and the wavelength of electrons.

Only the edges of the project (the command line, the add-on's dialog, a file's metadata) read
units; everything inside is metres. ``length("3.45um")`` is 3.45e-6; ``wavelength("300kV")``
is the relativistic de Broglie wavelength of electrons accelerated through 300 kV (1.9687 pm),
as electron microscopists state their wave.
"""

from __future__ import annotations

import math
import re

from .validate import InputError, shown

# CODATA 2018 (exact where SI defines them)
PLANCK = 6.62607015e-34  # h [J s]
ELECTRON_MASS = 9.1093837015e-31  # m_e [kg]
ELEMENTARY_CHARGE = 1.602176634e-19  # e [C]
LIGHT_SPEED = 299792458.0  # c [m/s]

# each unit as a power of ten of a metre: 5 µm is 5 / 10⁶ m, correctly rounded (5 · 1e-6 is not)
DECADES = {
    "pm": -12,
    "nm": -9,
    "um": -6,
    "µm": -6,
    "μm": -6,
    "micron": -6,
    "mm": -3,
    "cm": -2,
    "m": 0,
    "angstrom": -10,
    "å": -10,
}
METRES = {unit: 10.0**e for unit, e in DECADES.items()}
VOLTS = {"v": 1.0, "kv": 1e3, "mv": 1e6}
_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\d\s.].*)?$")


def electron_wavelength(voltage: float) -> float:
    """The wavelength [m] of electrons accelerated through ``voltage`` [V] (> 0), with the
    relativistic correction: λ = h / √(2·m·e·U·(1 + e·U/(2·m·c²)))."""
    if not (isinstance(voltage, (int, float)) and math.isfinite(voltage) and voltage > 0):
        raise InputError(f"accelerating voltage must be > 0 [V]; got {shown(voltage)}")
    energy = ELEMENTARY_CHARGE * voltage
    momentum = math.sqrt(
        2 * ELECTRON_MASS * energy * (1 + energy / (2 * ELECTRON_MASS * LIGHT_SPEED**2))
    )
    return PLANCK / momentum


def split(text: str, name: str) -> tuple[float, str | None]:
    """(the number, its unit or None) of ``text`` such as '3.45um', '633 nm', '300kV'."""
    match = _NUMBER.match(str(text))
    if not match:
        raise InputError(
            f"{name} must be a number with an optional unit (3.45um, 633nm, "
            f"0.05m, 300kV); got {text!r}"[:300]
        )
    value = float(match.group(1))
    if not math.isfinite(value):
        raise InputError(f"{name} must be finite; got {text!r}")
    unit = match.group(2)
    return value, None if unit is None else unit.strip()


def length(text: str, name: str, default_unit: str = "m") -> float:
    """``text`` (a number, with a unit of :data:`METRES` or in ``default_unit``) in metres."""
    value, unit = split(text, name)
    unit = default_unit if unit is None else unit
    decade = DECADES.get(unit, DECADES.get(unit.lower()))
    if decade is None:
        raise InputError(
            f"{name}: unknown unit {unit!r}; use one of {', '.join(sorted(DECADES))}"[:300]
        )
    return value / 10**-decade if decade < 0 else value * 10**decade


def wavelength(text: str, name: str = "wavelength", default_unit: str = "nm") -> float:
    """A wavelength [m] from ``text``: a length (in ``default_unit`` without a unit), or an
    electron microscope's accelerating voltage ('300kV', '1.2MV', '200000V')."""
    value, unit = split(text, name)
    if unit is not None and unit.lower() in VOLTS:
        if unit == "mV":  # millivolts: no electron microscope; MV is what was meant
            raise InputError(f"{name}: {text!r} is millivolts; write MV for megavolts")
        return electron_wavelength(value * VOLTS[unit.lower()])
    return length(text, name, default_unit)
