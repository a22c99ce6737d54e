"""Acquired holograms, as digital-holography labs process them: the carrier found, the
sideband filtered, the wave cleaned, refocused and viewed.

- ``carrier.py``: the +1 order's carrier found in the spectrum by a stated rule, its angle and
  azimuth; in-line holograms recognised
- ``filters.py``: the sideband filter (shape, edge, apodisation, radius in physical units),
  intensities subtracted, division by a reference (vacuum) hologram
- ``processing.py``: phase unwrapping, the phase ramp (tilt) and a background taken away
- ``focus.py``: numerical refocus and autofocus over a range of distances (Brenner, Sobel
  variance, Tenengrad, variance, Tamura, peak)
- ``scan.py``: a scan imported with its carrier (the order that focuses behind it), its
  object wave placed at its distance
- ``framing.py``: the objects' plane and a camera that frames it (pure arithmetic: Blender's
  process imports it)

The names below are imported on first use, so that ``framing`` comes without the OpenCL
stages the others use.
"""

from ..lazy import lazy_names

_API = {
    "Carrier": ".carrier",
    "InlineHologramError": ".carrier",
    "find_carrier": ".carrier",
    "METRICS": ".focus",
    "Focus": ".focus",
    "autofocus": ".focus",
    "decimate": ".focus",
    "depth_of_focus": ".focus",
    "focus_metric": ".focus",
    "refocus": ".focus",
    "fit_phase": ".processing",
    "remove_background": ".processing",
    "remove_tilt": ".processing",
    "unwrap": ".processing",
    "OrderWarning": ".scan",
    "import_acquired": ".scan",
    "object_hologram": ".scan",
    "default_camera": ".framing",
    "plane_bounds": ".framing",
    "stated_plane": ".framing",
    "Aperture": ".filters",
    "sideband": ".filters",
}
__all__ = [
    "METRICS",
    "Aperture",
    "Carrier",
    "Focus",
    "InlineHologramError",
    "OrderWarning",
    "autofocus",
    "decimate",
    "default_camera",
    "depth_of_focus",
    "find_carrier",
    "fit_phase",
    "focus_metric",
    "import_acquired",
    "object_hologram",
    "plane_bounds",
    "refocus",
    "remove_background",
    "remove_tilt",
    "sideband",
    "stated_plane",
    "unwrap",
]


__getattr__, __dir__ = lazy_names(__name__, _API)
