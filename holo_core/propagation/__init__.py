"""Wave propagation between planes, SI metres and radians, exp(+ikr) waves (Sect. IV).

grid.py: pixel centres, frequencies, padded sizes · convolution.py: the padded spectral
convolution on the device · angular_spectrum.py: Eq. 10-15 with band limit ·
rayleigh_sommerfeld.py: direct integration of Eq. 7 · tilt.py: spectrum rotation (Eq. 11) and
placed planes · resample.py: the four cases of Fig. 4 · fresnel.py: Fresnel and Fraunhofer.
"""

from .angular_spectrum import alias_free_distance, angular_spectrum, transfer_function
from .fresnel import fraunhofer, fresnel
from .rayleigh_sommerfeld import rayleigh_sommerfeld
from .resample import interpolation_matrix, resample
from .tilt import propagate_to_plane, tilt

__all__ = ["alias_free_distance", "angular_spectrum", "fraunhofer", "fresnel",
           "interpolation_matrix", "propagate_to_plane", "rayleigh_sommerfeld", "resample",
           "tilt", "transfer_function"]
