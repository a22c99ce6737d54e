"""The phase φ a phase-only SLM should show so that its light u = s·exp(iφ) (s the source
amplitude) forms target amplitudes a_p on one or several planes, each reached by a linear
propagation A_p (angular spectrum, Fresnel or the far field).

- :func:`gerchberg_saxton` alternates projections (Gerchberg & Saxton 1972; Fienup 1982):
  v_p = A_p·u, keep its phase and impose a_p, come back by A_pᴴ, keep the phase and impose s;
  with several planes it visits them in turn. For the far field, whose Aᴴ is its inverse up to
  a constant, the error never grows (Fienup's error reduction).
- :func:`optimise_phase` descends the loss L = Σ_p ‖σ·|A_p·u| − a_p‖² / Σ_p ‖a_p‖², σ the
  best scale in closed form (the loss does not ask the SLM for a given energy), with Adam
  (Kingma & Ba 2015). The gradient is exact and needs no autodiff framework:
  ∂L/∂φ = 2·Im(G·ū), G = Σ_p A_pᴴ(σ(σ|v_p| − a_p)·v_p/|v_p|)/Σ‖a_p‖², each A_pᴴ the adjoint
  of :mod:`holo_core.propagation.adjoint`.

The propagations run where they run (the device), the updates on the host in float64.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import validate
from ..propagation import angular_spectrum, fraunhofer, fresnel
from ..propagation.adjoint import adjoint
from ..validate import InputError

PROPAGATIONS = {"angular_spectrum": angular_spectrum, "fresnel": fresnel, "fraunhofer": fraunhofer}


class Retrieval(NamedTuple):
    """phase: (H, W) float64 [rad] in (−π, π]; errors: the normalised amplitude error
    ‖σ|A·u| − a‖/‖a‖ over all planes (σ the best scale) before each iteration and after
    the last."""

    phase: np.ndarray
    errors: list


def gerchberg_saxton(
    targets,
    *,
    wavelength,
    pitch,
    distances,
    propagation="angular_spectrum",
    source=1.0,
    iterations=50,
    seed=0,
    **settings,
) -> Retrieval:
    """Retrieve an SLM phase by Gerchberg–Saxton over the planes at ``distances``.

    Parameters
    ----------
    targets : (H, W) or sequence of (H, W) real arrays
        Target amplitudes ``|U|`` (not intensities), one per distance.
    wavelength : float
        λ [m].
    pitch : float
        The SLM's pitch [m].
    distances : float or sequence of float
        Distance [m] of each target plane (> 0 for the far field).
    propagation : {'angular_spectrum', 'fresnel', 'fraunhofer'}
        The propagation between the SLM and the planes.
    source : float or (H, W) array
        The illumination's amplitude on the SLM.
    iterations : int
        Iterations, in [0, 100000].
    seed : int
        Seed of the random starting phase.
    **settings
        Passed to the propagation (``padding``, ...).

    Returns
    -------
    Retrieval
        ``phase`` (H, W) float64 [rad] in (−π, π], and ``errors``: the normalised amplitude
        error over all planes before each iteration and after the last.

    Raises
    ------
    InputError
        Where a target, distance or setting is out of range, naming it.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import gerchberg_saxton
    >>> r = gerchberg_saxton(np.ones((32, 32)), wavelength=633e-9, pitch=8e-6, distances=0.1,
    ...                      iterations=5)
    >>> r.phase.shape, len(r.errors)
    ((32, 32), 6)
    """
    p = _Problem(targets, wavelength, pitch, distances, propagation, source, settings)
    iterations = validate.integer("iterations", iterations, 0, 100_000)
    phase = np.random.default_rng(validate.seed(seed)).uniform(-np.pi, np.pi, p.shape)
    errors = []
    for _ in range(iterations):
        u = p.source * np.exp(1j * phase)
        errors.append(p.error(p.forward_all(u)))
        for k in range(len(p.targets)):
            v = p.forward(k, u)
            v = p.targets[k] * np.exp(1j * np.angle(v))
            u = p.source * np.exp(1j * np.angle(p.backward(k, v)))
        phase = np.angle(u)
    errors.append(p.error(p.forward_all(p.source * np.exp(1j * phase))))
    return Retrieval(phase, errors)


def optimise_phase(
    targets,
    *,
    wavelength,
    pitch,
    distances,
    propagation="angular_spectrum",
    source=1.0,
    iterations=100,
    learning_rate=0.05,
    seed=0,
    phase=None,
    **settings,
) -> Retrieval:
    """Retrieve an SLM phase by gradient descent (Adam) for the planes at ``distances``.

    Parameters
    ----------
    targets, wavelength, pitch, distances, propagation, source, iterations, seed, **settings
        As for :func:`gerchberg_saxton` (``wavelength``, ``pitch``, ``distances`` [m]).
    learning_rate : float
        Adam's step [rad], > 0.
    phase : (H, W) float array, optional
        A starting phase [rad] (e.g. Gerchberg–Saxton's); default random from ``seed``.

    Returns
    -------
    Retrieval
        ``phase`` (H, W) float64 [rad] in (−π, π], and ``errors`` as for
        :func:`gerchberg_saxton`.

    Raises
    ------
    InputError
        Where ``learning_rate`` is not > 0, ``phase`` is not of the targets' shape, or another
        argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import optimise_phase
    >>> r = optimise_phase(np.ones((32, 32)), wavelength=633e-9, pitch=8e-6, distances=0.1,
    ...                    iterations=5)
    >>> r.phase.shape
    (32, 32)
    """
    p = _Problem(targets, wavelength, pitch, distances, propagation, source, settings)
    iterations = validate.integer("iterations", iterations, 0, 100_000)
    rate = validate.positive("learning_rate", learning_rate, "rad")
    if phase is None:
        phase = np.random.default_rng(validate.seed(seed)).uniform(-np.pi, np.pi, p.shape)
    else:
        phase = np.array(validate.host_field("phase", phase), np.float64)
        if phase.shape != p.shape:
            raise InputError(f"phase must be {p.shape}; got {phase.shape}")
    m, v = np.zeros(p.shape), np.zeros(p.shape)
    b1, b2, eps = 0.9, 0.999, 1e-8
    errors = []
    for t in range(1, iterations + 1):
        loss, grad = p.loss_and_gradient(phase)
        errors.append(float(np.sqrt(loss)))
        m = b1 * m + (1 - b1) * grad
        v = b2 * v + (1 - b2) * grad * grad
        phase = phase - rate * (m / (1 - b1**t)) / (np.sqrt(v / (1 - b2**t)) + eps)
    phase = np.angle(np.exp(1j * phase))
    errors.append(float(np.sqrt(p.loss_and_gradient(phase)[0])))
    return Retrieval(phase, errors)


class _Problem:
    """The planes, their propagations and adjoints, and the loss."""

    def __init__(self, targets, wavelength, pitch, distances, propagation, source, settings):
        name = validate.choice("propagation", propagation, tuple(PROPAGATIONS))
        self.method = PROPAGATIONS[name]
        self.adjoint = adjoint(self.method)
        self.far = name == "fraunhofer"
        distances = np.atleast_1d(
            np.asarray(
                validate.array("distances", distances, "a distance or a sequence of them [m]"),
                np.float64,
            )
        )
        if distances.ndim != 1 or not distances.size:
            raise InputError(
                f"distances must be a distance or a sequence of them [m]; got {distances!r}"
            )
        if isinstance(targets, np.ndarray) and targets.ndim == 2:
            targets = [targets]
        try:
            targets = [np.asarray(validate.host_field("targets", t), np.float64) for t in targets]
        except TypeError:
            raise InputError("targets must be an (H, W) amplitude or a sequence of them") from None
        if len(targets) != len(distances):
            raise InputError(
                f"targets and distances must pair up; got {len(targets)} targets "
                f"and {len(distances)} distances"
            )
        shapes = {t.shape for t in targets}
        if len(shapes) != 1 or any(np.iscomplexobj(t) or (t < 0).any() for t in targets):
            raise InputError(
                f"targets must be real amplitudes >= 0 of one shape; got shapes {sorted(shapes)}"
            )
        self.shape = targets[0].shape
        self.targets, self.distances = targets, [float(d) for d in distances]
        self.norm = sum(float(np.sum(t * t)) for t in targets)
        if self.norm == 0:
            raise InputError("targets must not all be zero")
        self.source = np.broadcast_to(np.asarray(source, np.float64), self.shape)
        if (self.source < 0).any() or not np.isfinite(self.source).all():
            raise InputError("source must be a finite amplitude >= 0, a number or an (H, W) array")
        self.kw = {"wavelength": wavelength, "pitch": pitch, **settings}

    def forward(self, k, u):
        out = self.method(u.astype(np.complex64), distance=self.distances[k], **self.kw)
        return (out[0] if self.far else out).astype(np.complex128)

    def backward(self, k, v):
        return self.adjoint(v.astype(np.complex64), distance=self.distances[k], **self.kw).astype(
            np.complex128
        )

    def forward_all(self, u):
        return [self.forward(k, u) for k in range(len(self.targets))]

    def scale(self, vs):
        """σ minimising Σ‖σ|v_p| − a_p‖²."""
        num = sum(float(np.sum(np.abs(v) * a)) for v, a in zip(vs, self.targets))
        den = sum(float(np.sum(np.abs(v) ** 2)) for v in vs)
        return num / den if den > 0 else 0.0

    def error(self, vs) -> float:
        s = self.scale(vs)
        return float(
            np.sqrt(
                sum(float(np.sum((s * np.abs(v) - a) ** 2)) for v, a in zip(vs, self.targets))
                / self.norm
            )
        )

    def loss_and_gradient(self, phase):
        u = self.source * np.exp(1j * phase)
        vs = self.forward_all(u)
        s = self.scale(vs)
        loss, g = 0.0, np.zeros(self.shape, np.complex128)
        for k, (v, a) in enumerate(zip(vs, self.targets)):
            mag = np.abs(v)
            r = s * mag - a
            loss += float(np.sum(r * r))
            g += self.backward(k, s * r * np.divide(v, mag, out=np.zeros_like(v), where=mag > 0))
        return loss / self.norm, 2 * np.imag(g * np.conj(u)) / self.norm
