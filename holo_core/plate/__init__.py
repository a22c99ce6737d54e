"""The plate hologram: a scene asset, recorded once on a plate in the scene for a viewing zone,
viewed by any camera in that zone.

- ``plan.py``: a plate's samples, wavelengths, emitters and costs, from its zone and the views
  it serves (pure arithmetic: no driver)
- ``carrier.py``: the spherical carrier converging on the zone that the samples are stored
  against, and the exact re-modulation to the physical object wave
- ``emitters.py``: the surfaces the zone sees, one emitter per resolved spot, and the zone
  points each is seen from (depth buffers over the zone)
- ``zone_sum.py``: the samples as a sum of the emitters' waves towards the zone (Eq. 3)
- ``sampling.py``: the point sums' pitch, wavelengths and band (Sect. V)
- ``point_sources.py``: the object wave of point emitters on the plate (Eq. 16-18)
- ``triangles.py``: the object wave of textured triangles, by spectrum rotation (Sect. IV-C)
- ``record.py``: the plate of meshes against its carrier; point sums (complex, or
  H = |O + R|² with its reference, Eq. 4, 19)
- ``reconstruction.py``: R'·H with the DC term suppressed (Sect. VI)
- ``tiles.py``: plates larger than memory, recorded tile by tile as Dask tasks into a tiled
  store (plates of meshes against their carrier; point sums)
- ``to_pupil.py``: the plate's light carried to a camera's entrance pupil (a carrier plate's
  by demodulation, decimation and a non-uniform FFT; a full-band one by the angular spectrum)
- ``view.py``: a camera's image of it, by the camera hologram's own pupil stage (Sect. VII)
- ``path.py``: a plate's parts along a camera path (a long dolly, an orbit), each facing its
  stretch (pure arithmetic: no driver)
- ``parts.py``: the parts recorded from one set of emitters, each frame viewed from the part
  that holds its pupil
"""

import sys
import types
from importlib import import_module

# the names below import their modules on first use: the planner (plan.py) is pure arithmetic,
# and Blender's process imports it without the OpenCL driver the recorder and the viewer load
_API = {"Reference": ".record", "record_hologram": ".record", "record_plate": ".record",
        "record_looks": ".record",
        "record_points": ".record", "reconstruct": ".reconstruction", "render_view": ".view",
        "physical_field": ".carrier", "parts_along": ".path", "record_set": ".parts",
        "render_set_view": ".parts",
        "find_carrier": "..acquired", "sideband": "..acquired"}  # their home: acquired/
__all__ = sorted(_API)


class _Package(types.ModuleType):
    """The package whose API names are its functions, also where a module of the same name
    was imported and set as the package's attribute."""

    def __getattribute__(self, name):
        if name in _API:
            return getattr(import_module(_API[name], __name__), name)
        return super().__getattribute__(name)

    def __dir__(self):
        return sorted({*super().__dir__(), *_API})


sys.modules[__name__].__class__ = _Package
