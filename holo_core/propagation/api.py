"""The propagation package's public names (:mod:`holo_core.propagation`): the plane functions
of its modules, each wrapped to take Fields and batches too (:func:`.batch.batched`) and to
carry its adjoint. Imported on the first use of one of them: the grid helpers
(:mod:`.grid`) stay pure arithmetic for the planner and Blender's process.
"""

import numpy as np

from .. import validate
from . import grid
from .angular_spectrum import angular_spectrum as _angular_spectrum
from .angular_spectrum import angular_spectrum_adjoint as _angular_spectrum_adjoint
from .batch import batched, rigid, translation
from .fresnel import fraunhofer as _fraunhofer
from .fresnel import fraunhofer_adjoint, fresnel_adjoint
from .fresnel import fresnel as _fresnel
from .rayleigh_sommerfeld import rayleigh_sommerfeld as _rayleigh_sommerfeld
from .resample import resample as _resample
from .tilt import propagate_to_plane as _propagate_to_plane
from .tilt import tilt as _tilt


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
angular_spectrum = batched(_angular_spectrum, moves=_shifted, grid_of=_scaled_grid)
fresnel = batched(_fresnel, moves=_shifted, grid_of=_scaled_grid)
fraunhofer = batched(
    _fraunhofer,
    returns_pitch=True,
    moves=lambda kw: translation(0.0, 0.0, kw["distance"]),
)
angular_spectrum.adjoint = batched(
    _angular_spectrum_adjoint, moves=_shifted_back, grid_of=_scaled_grid
)
fresnel.adjoint = batched(fresnel_adjoint, moves=_shifted_back, grid_of=_scaled_grid)
fraunhofer.adjoint = fraunhofer_adjoint
rayleigh_sommerfeld = batched(_rayleigh_sommerfeld, moves=_shifted, grid_of=_out_grid)
tilt = batched(_tilt, moves=lambda kw: rigid(kw["rotation"]), grid_of=_out_grid)
propagate_to_plane = batched(
    _propagate_to_plane,
    grid_of=_out_grid,
    moves=lambda kw: rigid(kw["rotation"], kw["position"]),
)
resample = batched(
    _resample,
    grid_of=lambda kw, shape, pitch: (
        validate.shape2d("out_shape", kw["out_shape"]),
        grid.pitch_pair(kw["out_pitch"], "out_pitch"),
    ),
)
