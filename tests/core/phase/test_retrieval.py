"""Phase retrieval: Gerchberg–Saxton's error never grows in the far field, the descent's
gradient is the loss's derivative, and both shape one or two planes."""

import numpy as np
import pytest

from holo_core.phase import gerchberg_saxton, optimise_phase
from holo_core.phase.retrieval import _Problem
from holo_core.validate import InputError

LAM, PITCH, N = 633e-9, 8e-6, 64


def ring(radius, width=3.0):
    y, x = np.indices((N, N)) - (N - 1) / 2
    return (np.abs(np.hypot(x, y) - radius) < width).astype(float)


def test_far_field_error_never_grows():
    """Fienup's error reduction: with the far field (Aᴴ its inverse up to a constant) each
    iteration's error is at most the last one's."""
    r = gerchberg_saxton(
        ring(12),
        wavelength=LAM,
        pitch=PITCH,
        distances=2.0,
        propagation="fraunhofer",
        iterations=30,
    )
    steps = np.diff(r.errors)
    assert (steps <= 1e-5).all(), f"largest growth {steps.max():.3g}"
    assert r.errors[-1] < 0.5 * r.errors[0], r.errors[::10]
    assert r.phase.shape == (N, N) and np.abs(r.phase).max() <= np.pi


def test_the_gradient_is_the_derivative(rng):
    """Along a random direction d, (L(φ + hd) − L(φ − hd))/2h equals ∇L·d, two planes by the
    angular spectrum (the adjoint's gradient, no autodiff)."""
    p = _Problem([ring(8), ring(16)], LAM, PITCH, [2e-3, 4e-3], "angular_spectrum", 1.0, {})
    phase = rng.uniform(-np.pi, np.pi, (N, N))
    d = rng.normal(size=(N, N))
    _, grad = p.loss_and_gradient(phase)
    h = 1e-3
    numeric = (p.loss_and_gradient(phase + h * d)[0] - p.loss_and_gradient(phase - h * d)[0]) / (
        2 * h
    )
    analytic = float(np.sum(grad * d))
    assert abs(numeric - analytic) <= 2e-3 * abs(analytic), (numeric, analytic)


def test_two_planes_by_descent_and_by_projections():
    """Two rings 2 mm apart: Adam from a Gerchberg–Saxton start lowers the error further."""
    targets, z = [ring(8), ring(16)], [2e-3, 4e-3]
    gs = gerchberg_saxton(targets, wavelength=LAM, pitch=PITCH, distances=z, iterations=20)
    gd = optimise_phase(
        targets, wavelength=LAM, pitch=PITCH, distances=z, iterations=60, phase=gs.phase
    )
    assert gs.errors[-1] < gs.errors[0], gs.errors[::5]
    assert gd.errors[-1] < 0.9 * gs.errors[-1], (gs.errors[-1], gd.errors[-1])
    fresh = optimise_phase(targets, wavelength=LAM, pitch=PITCH, distances=z, iterations=60)
    assert fresh.errors[-1] < 0.8 * fresh.errors[0], fresh.errors[::20]


def test_bad_problems_are_refused():
    with pytest.raises(InputError, match="pair up"):
        gerchberg_saxton([ring(8)], wavelength=LAM, pitch=PITCH, distances=[1e-3, 2e-3])
    with pytest.raises(InputError, match="propagation must be one of"):
        gerchberg_saxton(ring(8), wavelength=LAM, pitch=PITCH, distances=1e-3, propagation="rs")
    with pytest.raises(InputError, match="real amplitudes >= 0"):
        optimise_phase(-ring(8), wavelength=LAM, pitch=PITCH, distances=1e-3)
