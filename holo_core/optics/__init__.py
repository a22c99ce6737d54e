"""What a camera does with light, for both renderers.

- ``pupil.py``: :class:`Pupil`, the entrance pupil (diameter, thin-lens focus, apodization), and
  the pinhole rules side by side
- ``depth.py``: depth from the two-wavelength phase difference (Eq. 26–30)
- ``speckle.py``: averaging, downsampling and the speckle contrast (Sect. VII-E), and the
  speckle a uniform surface keeps through a view's looks, fine pixels and defocus
- ``imaging.py``: the pupil → image stage both renderers share (iris, thin lens, the spectrum
  read at the pixels), and a view assembled from colour, coverage and the depth pair
- ``lens.py``: a thin lens's phase on a field or a Field (:func:`thin_lens`)
- ``metrics.py``: image quality against a reference, :func:`psnr` and :func:`ssim`
"""

from ..lazy import lazy_names

# imported on first use: depth.py and pupil.py are arithmetic the planner uses without the
# OpenCL driver that lens.py's propagation loads
_API = {"thin_lens": ".lens", "psnr": ".metrics", "ssim": ".metrics", "Pupil": ".pupil"}
__all__ = ["Pupil", "psnr", "ssim", "thin_lens"]


__getattr__, __dir__ = lazy_names(__name__, _API)
