"""What a camera does with light, for both renderers.

- ``pupil.py``: :class:`Pupil`, the entrance pupil (diameter, thin-lens focus, apodization), and
  the pinhole rules side by side
- ``depth.py``: depth from the two-wavelength phase difference (Eq. 26–30)
- ``speckle.py``: averaging, downsampling and the speckle contrast (Sect. VII-E)
"""

from .pupil import Pupil

__all__ = ["Pupil"]
