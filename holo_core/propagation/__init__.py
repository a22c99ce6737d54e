"""Wave propagation between planes, SI metres and radians, exp(+ikr) waves (Sect. IV).

grid.py: pixel centres, frequencies, padded sizes · convolution.py: the padded spectral
convolution on the device · angular_spectrum.py: Eq. 10-15 with band limit ·
rayleigh_sommerfeld.py: direct integration of Eq. 7 · tilt.py: spectrum rotation (Eq. 11) and
placed planes · resample.py: the four cases of Fig. 4 · fresnel.py: Fresnel and Fraunhofer.
"""

_API = {"alias_free_distance": ".angular_spectrum", "angular_spectrum": ".angular_spectrum",
        "transfer_function": ".angular_spectrum", "fraunhofer": ".fresnel",
        "fresnel": ".fresnel", "rayleigh_sommerfeld": ".rayleigh_sommerfeld",
        "interpolation_matrix": ".resample", "resample": ".resample",
        "propagate_to_plane": ".tilt", "tilt": ".tilt"}
__all__ = sorted(_API)


def __getattr__(name):  # imported on first use: grid.py alone stays free of OpenCL
    if name not in _API:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from importlib import import_module
    return getattr(import_module(_API[name], __name__), name)
