"""The plate hologram: recorded once on a plate in the scene, viewed by any camera in front.

- ``sampling.py``: pitch, wavelengths and band chosen from the scene and the plate (Sect. V)
- ``point_sources.py``: the object wave of point emitters on the plate (Eq. 16-18)
- ``triangles.py``: the object wave of textured triangles, by spectrum rotation (Sect. IV-C)
- ``record.py``: reference wave and H = |O + R|² (Eq. 4, 19)
- ``reconstruct.py``: R'·H with the DC term suppressed (Sect. VI)
- ``sideband.py``: the sideband filter of an acquired off-axis hologram, its carrier found
  from the metadata or the spectrum
- ``view.py``: a camera's image of the reconstructed wave (Sect. VII)
"""

from .reconstruct import reconstruct
from .record import Reference, record_hologram, record_points
from .sideband import find_carrier, sideband
from .view import render_view

__all__ = ["Reference", "find_carrier", "reconstruct", "record_hologram", "record_points",
           "render_view", "sideband"]
