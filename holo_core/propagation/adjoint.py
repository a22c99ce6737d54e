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
    """Return the adjoint of a linear propagation, called with the same keywords.

    Parameters
    ----------
    propagation : callable
        One of ``angular_spectrum``, ``fresnel``, ``fraunhofer``, ``thin_lens``.

    Returns
    -------
    callable
        Its adjoint Aᴴ (<A·x, y> = <x, Aᴴ·y>): ``adjoint(angular_spectrum)(y, wavelength=λ,
        pitch=p, distance=z)`` maps a field on the target plane back to the source's grid.

    Raises
    ------
    InputError
        Where ``propagation`` has no adjoint (is none of the four).

    Examples
    --------
    The angular spectrum is unitary within its band: the adjoint undoes it.

    >>> import numpy as np
    >>> from holo_core import adjoint, angular_spectrum
    >>> u = np.ones((64, 64), complex)
    >>> v = angular_spectrum(u, wavelength=633e-9, pitch=4e-6, distance=1e-3)
    >>> back = adjoint(angular_spectrum)(v, wavelength=633e-9, pitch=4e-6, distance=1e-3)
    >>> round(float(abs(back[32, 32])), 3)
    1.0
    """
    transposed = getattr(propagation, "adjoint", None)
    if not callable(transposed):
        raise validate.InputError(
            f"propagation must be angular_spectrum, fresnel, fraunhofer "
            f"or thin_lens; got {propagation!r}"[:300]
        )
    return transposed


__all__ = ["adjoint", "fraunhofer_adjoint"]
