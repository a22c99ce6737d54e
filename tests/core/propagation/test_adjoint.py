"""Each propagation's adjoint passes the dot-product test <A·x, y> = <x, Aᴴ·y> to float32
precision, on the host and on the device."""

import numpy as np
import pytest
from accuracy import ADJOINT

from holo_core import to_device
from holo_core.optics.lens import thin_lens
from holo_core.propagation import angular_spectrum, fraunhofer, fresnel
from holo_core.propagation.adjoint import adjoint
from holo_core.validate import InputError

LAM, PITCH = 633e-9, 2e-6
CASES = {
    "angular_spectrum": (
        angular_spectrum,
        {"distance": 3e-3, "offset": (2e-5, -1e-5), "padding": 2},
    ),
    "angular_spectrum backwards": (angular_spectrum, {"distance": -1e-3}),
    "fresnel": (fresnel, {"distance": 0.02, "offset": (1e-5, 0.0)}),
    "fraunhofer": (fraunhofer, {"distance": 0.5}),
    "thin_lens": (thin_lens, {"focal_length": 0.01}),
}


def dot(a, b) -> complex:
    return complex(np.vdot(np.asarray(b, np.complex128), np.asarray(a, np.complex128)))


@pytest.mark.parametrize("on_device", [False, True])
@pytest.mark.parametrize("name", CASES)
def test_dot_product(rng, name, on_device):
    method, settings = CASES[name]
    kw = {"wavelength": LAM, "pitch": PITCH, **settings}
    shape = (48, 64)
    x = (rng.normal(size=shape) + 1j * rng.normal(size=shape)).astype(np.complex64)
    y = (rng.normal(size=shape) + 1j * rng.normal(size=shape)).astype(np.complex64)
    ax = method(to_device(x) if on_device else x, **kw)
    ax = ax[0] if isinstance(ax, tuple) else ax
    aty = adjoint(method)(to_device(y) if on_device else y, **kw)
    if on_device:
        ax, aty = ax.get(), aty.get()
    lhs, rhs = dot(ax, y), dot(x, aty)
    err = abs(lhs - rhs) / (np.linalg.norm(ax) * np.linalg.norm(y))
    assert err <= ADJOINT, f"{name}: |<Ax,y> - <x,Aᴴy>| / (|Ax||y|) = {err:.3g}"


def test_only_linear_propagations_have_one():
    with pytest.raises(InputError, match="propagation must be"):
        adjoint(np.fft.fft2)
