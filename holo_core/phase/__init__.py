"""Phase for displays and optimisation: what a phase-only SLM should show.

- ``retrieval.py``: Gerchberg–Saxton and gradient descent (Adam) of a phase over one or several
  planes, gradients from the propagations' adjoints (:mod:`holo_core.propagation.adjoint`)
- ``encoding.py``: phase-only encodings of a complex field (double-phase)
- ``display.py``: displays (presets, bit depth, phase range) and a plate's pattern for one
- ``slm.py``: a phase SLM as a lab drives it: lasers, phase tables, eye box, volume, checks
- ``levels.py``: the phase each code shows and the code nearest a wanted phase
- ``encode.py``: a complex wave encoded for a phase SLM (double-phase, gradient descent over
  the focal stack, Gerchberg–Saxton), quantised through its table
- ``display_frame.py``: one frame of a display's animation: the recorded waves encoded, its
  patterns, layouts and focal stack written as one set (the add-on's Render Animation)
- ``stack.py``: the display's focal stack (filter, pupil, band-limited angular spectrum) and
  its PSNR and SSIM against the complex wave's
"""

from .display import Display, display_preset
from .encode import Pattern, encode
from .encoding import double_phase
from .export import Frame, export_frame
from .levels import quantise, response
from .retrieval import Retrieval, gerchberg_saxton, optimise_phase
from .slm import EyeBox, Laser, PhaseTable, SLMSetup, check_scene, read_phase_table
from .stack import Comparison, EyePupil, Optics, compare

__all__ = [
    "Comparison",
    "Display",
    "EyeBox",
    "EyePupil",
    "Frame",
    "Laser",
    "Optics",
    "Pattern",
    "PhaseTable",
    "Retrieval",
    "SLMSetup",
    "check_scene",
    "compare",
    "display_preset",
    "double_phase",
    "encode",
    "export_frame",
    "gerchberg_saxton",
    "optimise_phase",
    "quantise",
    "read_phase_table",
    "response",
]
