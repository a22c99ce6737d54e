"""Wave propagation between planes, SI metres and radians, exp(+ikr) waves (Sect. IV).

grid.py: pixel centres, frequencies, padded sizes · convolution.py: the padded spectral
convolution · angular_spectrum.py: Eq. 10-15 with band limit ·
rayleigh_sommerfeld.py: direct integration of Eq. 7 · tilt.py: spectrum rotation (Eq. 11) and
placed planes · resample.py: the four cases of Fig. 4 · fresnel.py: Fresnel and Fraunhofer ·
batch.py: Fields and batches through each of them (the public names here, each carrying its
adjoint) · transfer.py: transfer functions, float64 on the host and on the device ·
adjoint.py: a propagation's adjoint.
"""

from ..lazy import lazy_package

# the public names import their module (and the OpenCL driver it loads) on first use; a
# name that is also a module's (angular_spectrum, tilt, …) stays the public function after
# that module is imported, as the package's attribute would otherwise become the module
_API = {
    "alias_free_distance": ".angular_spectrum",
    "angular_spectrum": ".api",
    "batched": ".batch",
    "fraunhofer": ".api",
    "fresnel": ".api",
    "interpolation_matrix": ".resample",
    "propagate_to_plane": ".api",
    "rayleigh_sommerfeld": ".api",
    "resample": ".api",
    "tilt": ".api",
    "transfer_function": ".transfer",
}
__all__ = sorted(_API)


lazy_package(__name__, _API)
