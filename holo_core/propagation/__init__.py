"""Wave propagation between planes, SI metres and radians, exp(+ikr) waves (Sect. IV).

grid.py: pixel centres, frequencies, padded sizes · convolution.py: the padded spectral
convolution · angular_spectrum.py: Eq. 10-15 with band limit ·
rayleigh_sommerfeld.py: direct integration of Eq. 7 · tilt.py: spectrum rotation (Eq. 11) and
placed planes · resample.py: the four cases of Fig. 4 · fresnel.py: Fresnel and Fraunhofer ·
batch.py: Fields and batches through each of them (the public names here, each carrying its
adjoint) · transfer.py: transfer functions, float64 on the host and on the device ·
adjoint.py: a propagation's adjoint.
"""

import numpy as np

from .. import validate
from . import angular_spectrum as _asm_module
from . import fresnel as _fresnel_module
from . import grid
from . import rayleigh_sommerfeld as _rs_module
from . import resample as _resample_module
from . import tilt as _tilt_module
from .angular_spectrum import alias_free_distance
from .batch import batched, rigid, translation
from .resample import interpolation_matrix
from .transfer import transfer_function


def _shifted(kw):
    return translation(*kw.get("offset", (0.0, 0.0)), kw["distance"])


def _shifted_back(kw):  # where an adjoint's output lies: the source's plane
    x0, y0 = kw.get("offset", (0.0, 0.0))
    return translation(-x0, -y0, -np.asarray(kw["distance"]))


def _out_grid(kw, shape, pitch):
    shape = (
        validate.shape2d("out_shape", kw["out_shape"]) if kw.get("out_shape") is not None else shape
    )
    return shape, grid.pitch_pair(kw["out_pitch"], "out_pitch") if kw.get(
        "out_pitch"
    ) is not None else pitch


def _scaled_grid(kw, shape, pitch):  # scaled.py's defaults: the input's window at out_pitch
    out = (
        grid.pitch_pair(kw["out_pitch"], "out_pitch") if kw.get("out_pitch") is not None else pitch
    )
    if kw.get("out_shape") is not None:
        return validate.shape2d("out_shape", kw["out_shape"]), out
    return (
        max(1, round(shape[0] * pitch[1] / out[1])),
        max(1, round(shape[1] * pitch[0] / out[0])),
    ), out


# the public names: plane functions that also take Fields and batches (batch.py)
angular_spectrum = batched(_asm_module.angular_spectrum, moves=_shifted, grid_of=_scaled_grid)
fresnel = batched(_fresnel_module.fresnel, moves=_shifted, grid_of=_scaled_grid)
fraunhofer = batched(
    _fresnel_module.fraunhofer,
    returns_pitch=True,
    moves=lambda kw: translation(0.0, 0.0, kw["distance"]),
)
angular_spectrum.adjoint = batched(
    _asm_module.angular_spectrum_adjoint, moves=_shifted_back, grid_of=_scaled_grid
)
fresnel.adjoint = batched(
    _fresnel_module.fresnel_adjoint, moves=_shifted_back, grid_of=_scaled_grid
)
fraunhofer.adjoint = _fresnel_module.fraunhofer_adjoint
rayleigh_sommerfeld = batched(_rs_module.rayleigh_sommerfeld, moves=_shifted, grid_of=_out_grid)
tilt = batched(_tilt_module.tilt, moves=lambda kw: rigid(kw["rotation"]), grid_of=_out_grid)
propagate_to_plane = batched(
    _tilt_module.propagate_to_plane,
    grid_of=_out_grid,
    moves=lambda kw: rigid(kw["rotation"], kw["position"]),
)
resample = batched(
    _resample_module.resample,
    grid_of=lambda kw, shape, pitch: (
        validate.shape2d("out_shape", kw["out_shape"]),
        grid.pitch_pair(kw["out_pitch"], "out_pitch"),
    ),
)

__all__ = [
    "alias_free_distance",
    "angular_spectrum",
    "batched",
    "fraunhofer",
    "fresnel",
    "interpolation_matrix",
    "propagate_to_plane",
    "rayleigh_sommerfeld",
    "resample",
    "tilt",
    "transfer_function",
]
