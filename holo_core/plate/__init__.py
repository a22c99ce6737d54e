"""The plate hologram: a scene asset, recorded once on a plate in the scene for a viewing zone,
viewed by any camera in that zone.

- ``sampling.py``: pitch, wavelengths and band planned from the zone and the optics (Sect. V)
- ``point_sources.py``: the object wave of point emitters on the plate (Eq. 16-18)
- ``triangles.py``: the object wave of textured triangles, by spectrum rotation (Sect. IV-C)
- ``slabs.py``: the object wave of meshes with occlusion: emitters on depth slabs, silhouette
  masks (Matsushima)
- ``record.py``: the plate (complex, or H = |O + R|² with its reference, Eq. 4, 19)
- ``reconstruct.py``: R'·H with the DC term suppressed (Sect. VI)
- ``sideband.py``: the sideband filter of an acquired off-axis hologram, its carrier found
  from the metadata or the spectrum
- ``to_pupil.py``: the plate's field carried to a camera's entrance pupil
- ``view.py``: a camera's image of it, by the camera hologram's own pupil stage (Sect. VII)
"""

from .reconstruct import reconstruct
from .record import Reference, record_hologram, record_plate, record_points
from .sideband import find_carrier, sideband
from .view import render_view

__all__ = ["Reference", "find_carrier", "reconstruct", "record_hologram", "record_plate",
           "record_points", "render_view", "sideband"]
