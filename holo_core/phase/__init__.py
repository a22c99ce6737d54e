"""Phase for displays and optimisation: what a phase-only SLM should show.

- ``retrieval.py``: Gerchberg–Saxton and gradient descent (Adam) of a phase over one or several
  planes, gradients from the propagations' adjoints (:mod:`holo_core.propagation.adjoint`)
- ``encoding.py``: phase-only encodings of a complex field (double-phase)
"""

from .encoding import double_phase
from .retrieval import Retrieval, gerchberg_saxton, optimise_phase

__all__ = ["Retrieval", "double_phase", "gerchberg_saxton", "optimise_phase"]
