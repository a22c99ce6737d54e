"""The camera hologram: the object wave on a virtual plate at the camera's entrance pupil, and
the image the camera forms from it (Sect. VII: any wave field can be evaluated on the aperture
of an arbitrarily placed camera).

- ``optics.py``: the pupil's sampling: its wavelength, bins and depth layers
- ``raster.py``: one emitter per direction the camera resolves (a depth-buffered raster)
- ``recording.py``: the object wave on the pupil by depth layers, and the paper's intensity
  hologram of it (Sect. V–VI)
- ``render.py``: the image, its coverage and its depth
"""

from ..lazy import lazy_names

# the renderer imports its module (and the OpenCL driver) on first use: the optics and the
# raster are pure arithmetic, and Blender's process reads them for the estimates
_API = {"render_camera": ".render"}
__all__ = sorted(_API)
__getattr__, __dir__ = lazy_names(__name__, _API)
