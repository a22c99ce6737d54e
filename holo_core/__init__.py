"""Holo: holographic scene representation and wave-based image synthesis.

Conventions (README): SI metres and radians; the hologram plane is z = 0 and light travels
towards +z; fields are exp(+ikr) waves (time dependence exp(-iωt)); arrays are [row, col] =
[y, x] with column j at x = (j - (W-1)/2)·pitch.
"""

__version__ = "0.1.0"
