"""Adjoints of the linear propagations, for gradients without an autodiff framework.

A propagation A (field on one grid -> field on another) has the adjoint Aᴴ with
<A·x, y> = <x, Aᴴ·y> for all x, y: the gradient of a loss of A·x with respect to x is Aᴴ of the
gradient with respect to A·x. Each propagation's adjoint is defined beside it and carried as
its ``adjoint`` attribute: the angular spectrum's and Fresnel's (to −z, the offset negated) in
angular_spectrum.py and fresnel.py, the far field's there too, the thin lens's (the lens of
focal length −f) in optics/lens.py. ``tests/core/propagation/test_adjoint.py`` holds each to
the dot-product test in float32.
"""

from __future__ import annotations

from .. import validate
from .fresnel import fraunhofer_adjoint


def adjoint(propagation):
    """The adjoint of ``propagation`` (one of ``angular_spectrum``, ``fresnel``,
    ``fraunhofer``, ``thin_lens``), called with the same keywords: ``adjoint(angular_spectrum)
    (y, wavelength=λ, pitch=p, distance=z)`` maps a field on the target plane back to the
    source's grid."""
    transposed = getattr(propagation, "adjoint", None)
    if not callable(transposed):
        raise validate.InputError(f"propagation must be angular_spectrum, fresnel, fraunhofer "
                                  f"or thin_lens; got {propagation!r}"[:300])
    return transposed


__all__ = ["adjoint", "fraunhofer_adjoint"]
