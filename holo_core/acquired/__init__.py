"""Acquired holograms, as digital-holography labs process them: the carrier found, the
sideband filtered, the wave cleaned, refocused and viewed.

- ``carrier.py``: the +1 order's carrier found in the spectrum by a stated rule, its angle and
  azimuth; in-line holograms recognised
- ``sideband.py``: the sideband filter (shape, edge, apodisation, radius in physical units),
  intensities subtracted, division by a reference (vacuum) hologram
- ``processing.py``: phase unwrapping, the phase ramp (tilt) and a background taken away
- ``focus.py``: numerical refocus and autofocus over a range of distances (Brenner, Sobel
  variance, Tenengrad, variance, Tamura, peak)
- ``scan.py``: a scan to a view: imported with its carrier (the order that focuses behind
  it), the object wave placed at its distance, a camera that frames it
"""

from .carrier import Carrier, InlineHologramError, find_carrier
from .focus import METRICS, Focus, autofocus, decimate, depth_of_focus, focus_metric, refocus
from .processing import fit_phase, remove_background, remove_tilt, unwrap
from .scan import OrderWarning, default_camera, import_acquired, object_hologram
from .sideband import Aperture, sideband

__all__ = ["METRICS", "Aperture", "Carrier", "Focus", "InlineHologramError", "OrderWarning",
           "autofocus", "decimate", "default_camera", "depth_of_focus", "find_carrier", "fit_phase",
           "focus_metric", "import_acquired", "object_hologram", "refocus", "remove_background",
           "remove_tilt", "sideband", "unwrap"]
