"""Adjoints of the linear propagations, for gradients without an autodiff framework.

A propagation A (field on one grid -> field on another) has the adjoint Aᴴ with
<A·x, y> = <x, Aᴴ·y> for all x, y: the gradient of a loss of A·x with respect to x is Aᴴ of the
gradient with respect to A·x. Here:

- the angular spectrum pads, transforms, multiplies by H, transforms back and crops at the same
  place: Aᴴ multiplies by H̄ instead, and H̄(z, x0, y0) = H(−z, −x0, −y0) (its band limit
  |x0 − z·f/fz| too), so Aᴴ is the angular spectrum to −z with the offset negated;
- Fresnel likewise (its kept rays |x0 − λz·f| too);
- the far field is post·FFT(pre·u): Aᴴ·y = pre̅·FFTᴴ(post̅·y), FFTᴴ the unnormalised inverse;
- a thin lens multiplies by t: Aᴴ multiplies by t̄, the lens of focal length −f.

``tests/core/propagation/test_adjoint.py`` holds each to the dot-product test in float32.
"""

from __future__ import annotations

import math

import numpy as np

from .. import validate
from ..opencl import as_device, like_input
from ..opencl.arrays import cached, copy
from ..scene.field import Field
from . import grid
from .batch import batched
from .convolution import multiply
from .fresnel import centred_ramp, far_factor


def adjoint(propagation):
    """The adjoint of ``propagation`` (one of ``angular_spectrum``, ``fresnel``,
    ``fraunhofer``, ``thin_lens``), called with the same keywords: ``adjoint(angular_spectrum)
    (y, wavelength=λ, pitch=p, distance=z)`` maps a field on the target plane back to the
    source's grid."""
    from ..optics.lens import thin_lens
    from . import angular_spectrum, fraunhofer, fresnel
    if propagation is angular_spectrum or propagation is fresnel:
        def transposed(field, **kw):
            x0, y0 = validate.pair("offset", kw.get("offset", (0.0, 0.0)), "m")
            return propagation(field, **{**kw, "distance": -np.asarray(kw["distance"]),
                                         "offset": (-x0, -y0)})
    elif propagation is thin_lens:
        def transposed(field, **kw):
            return thin_lens(field, **{**kw, "focal_length": -kw["focal_length"]})
    elif propagation is fraunhofer:
        return fraunhofer_adjoint
    else:
        raise validate.InputError(f"propagation must be angular_spectrum, fresnel, fraunhofer "
                                  f"or thin_lens; got {propagation!r}"[:300])
    transposed.__name__ = f"adjoint_{propagation.__name__}"
    transposed.__doc__ = f"The adjoint of {propagation.__name__} (same keywords)."
    return transposed


def _fraunhofer_adjoint(field, *, wavelength, pitch, distance):
    """The far field's adjoint: from its grid back to the source grid of ``pitch`` [m]."""
    wavelength, pitch = grid.wave(wavelength, pitch)
    z = validate.positive("distance", validate.within("distance", distance,
                                                      validate.MAX_LENGTH), "m")
    rt, dev, from_host = as_device(field)
    h, w = dev.shape
    conj_pre, _ = cached(rt, ("centred-dft-adjoint", (h, w)),
                         lambda: (centred_ramp((h, w)).conj(), []))
    conj_post, _ = cached(rt, ("fraunhofer-adjoint", (h, w), wavelength, pitch, z),
                          lambda: (far_factor((h, w), wavelength, pitch, z).conj(), []))
    out = copy(dev)
    multiply(rt, out, conj_post)
    rt.fft.backward(out)
    multiply(rt, out, conj_pre)
    return like_input(out, from_host)


_batched_fraunhofer_adjoint = batched(_fraunhofer_adjoint)


def fraunhofer_adjoint(field, *, wavelength, pitch, distance):
    """The adjoint of :func:`~holo_core.propagation.fraunhofer`: a field on the far field's
    grid back to the source grid. ``pitch`` [m] is the *source* grid's, as given to
    fraunhofer; ``wavelength``, ``distance`` [m] (scalars or arrays over a batch). Arrays
    (H, W) or (..., H, W), NumPy or device; complex64 like the input."""
    if isinstance(field, Field):
        raise validate.InputError("fraunhofer_adjoint takes arrays: a Field carries the far "
                                  "field's pitch, and the adjoint needs the source's")
    return _batched_fraunhofer_adjoint(field, wavelength=wavelength, pitch=pitch,
                                       distance=distance)

__all__ = ["adjoint", "fraunhofer_adjoint"]
