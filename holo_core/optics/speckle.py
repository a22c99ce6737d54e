"""Speckle reduction (Sect. VII-E): temporal composition of renders with independent random
emitter phases (mean or maximum), and spatial low-pass plus downsampling; the speckle a
plate view of a uniform surface keeps (:func:`uniform_surface_variance`, the plan's model of
how many looks and fine pixels a scene needs)."""

from __future__ import annotations

import math

import numpy as np

from ..validate import InputError


def compose(intensities, how="mean") -> np.ndarray:
    """Combine N intensity images of the same view: 'mean' (speckle contrast falls as 1/√N
    for fully developed speckle) or 'max' (tends to (ΣA)² where few emitters interfere)."""
    stack = np.stack(intensities)
    if how == "mean":
        return stack.mean(0)
    if how == "max":
        return stack.max(0)
    raise InputError(f"composition must be 'mean' or 'max'; got {how!r}")


def downsample(image, factor: int) -> np.ndarray:
    """Average ``factor``×``factor`` blocks of (H·f, W·f[, C]): a box low-pass, then sampling."""
    if factor == 1:
        return image
    h, w = image.shape[0] // factor, image.shape[1] // factor
    blocks = image[: h * factor, : w * factor].reshape(h, factor, w, factor, *image.shape[2:])
    return blocks.mean((1, 3))


def box_mean(image, radius: int) -> np.ndarray:
    """The mean over (2r+1)² neighbourhoods, edges repeated: a symmetric low-pass, so a step
    edge keeps its half-way crossing where it was."""
    if radius == 0:
        return image
    image = np.asarray(image)  # float32 stays float32: a sum of nine carries 5e-7 at most
    a = np.pad(image if image.dtype.kind == "f" else image.astype(np.float64), radius, mode="edge")
    n = 2 * radius + 1
    h, w = a.shape[0] - 2 * radius, a.shape[1] - 2 * radius
    rows = a[:h].copy()  # the shifted copies summed in place: no running sum's rounding
    for i in range(1, n):  # to carry, and no temporary array for each shifted copy
        rows += a[i : i + h]
    out = rows[:, :w].copy()
    for j in range(1, n):
        out += rows[:, j : j + w]
    out *= out.dtype.type(1 / (n * n))
    return out


def pick_brightest(values, brightness, factor: int) -> np.ndarray:
    """Per ``factor``×``factor`` block, the value at its brightest sample (depth is not
    averaged across an edge)."""
    if factor == 1:
        return values
    h, w = values.shape[0] // factor, values.shape[1] // factor

    def blocks(a):
        return (
            a[: h * factor, : w * factor]
            .reshape(h, factor, w, factor)
            .transpose(0, 2, 1, 3)
            .reshape(h, w, factor * factor)
        )

    best = np.argmax(blocks(brightness), -1)[..., None]
    return np.take_along_axis(blocks(values), best, -1)[..., 0]


def contrast(intensity, mask=None) -> float:
    """Speckle contrast σ/⟨I⟩ over ``mask`` (all pixels by default)."""
    i = np.asarray(intensity, np.float64)
    i = i[mask] if mask is not None else i.ravel()
    return float(i.std() / i.mean())


PUPIL_TAPER = 0.1  # the iris's raised-cosine rim, a fraction of its radius (imaging.IRIS_TAPER)
# the simulated field's samples a pixel: fine pixels of 2, 3 and 4 and emitters half a pixel apart
# all fall on them
SAMPLES_PER_PIXEL = 24


def coded_look_codes(looks: int):
    """The codes (k, m) of ``looks`` coded looks of one seed (the plate's look_code): the
    checkerboard pair (0, 2) and (3, 2), m² looks (k, m) for k < m²; None for other counts
    (independent random phases)."""
    if looks == 2:
        return [(0, 2), (3, 2)]
    m = math.isqrt(looks)
    return [(k, m) for k in range(looks)] if looks > 1 and m * m == looks else None


def uniform_surface_variance(
    blur: float, looks: int, supersample: int, *, pixels=32, seeds=2, spacing=0.5
) -> float:
    """The relative variance (σ/⟨I⟩)² of a plate view's pixels on a uniform surface.

    The surface's emitters lie on a lattice ``spacing`` pixels apart (a plate's: one per
    resolved spot λ/D, half a pixel), each with a random phase shifted by its look's code
    (:func:`coded_look_codes`); each look's field is the emitters' sum through the camera's
    pupil (the iris with its cosine rim, defocused so that a point spreads over ``blur``
    pixels, its geometric blur diameter D·|1/z − 1/f| over the pixel angle), its intensity
    sampled at ``supersample`` fine pixels a pixel and averaged over each pixel, and the
    looks' mean taken, as :func:`holo_core.render_view` composes them. The lattice is
    periodic over ``pixels`` pixels (no borders); ``seeds`` draws are averaged.

    Parameters
    ----------
    blur : float
        Defocus blur diameter [px].
    looks : int
        Looks composed (coded where :func:`coded_look_codes` has codes).
    supersample : int
        Fine pixels a pixel (per axis): 1, 2, 3, 4, 6, 8, 12 or 24.
    pixels, seeds : int
        The simulated patch's size [px] and the draws averaged.
    spacing : float
        The emitters' spacing [px]: a multiple of 1/24.

    Returns
    -------
    float
        (σ/⟨I⟩)² of the pixels.

    Examples
    --------
    >>> from holo_core.optics.speckle import uniform_surface_variance
    >>> one = uniform_surface_variance(0.0, 1, 2, pixels=16, seeds=1)
    >>> four = uniform_surface_variance(0.0, 4, 2, pixels=16, seeds=1)
    >>> bool(four < one / 4)  # coded looks cancel more than four independent ones
    True
    """
    n = pixels * SAMPLES_PER_PIXEL
    if not isinstance(supersample, int) or supersample < 1 or SAMPLES_PER_PIXEL % supersample:
        raise InputError(f"supersample must divide {SAMPLES_PER_PIXEL}; got {supersample!r}")
    step = round(spacing * SAMPLES_PER_PIXEL)
    if step < 1 or abs(step - spacing * SAMPLES_PER_PIXEL) > 1e-9 or n % step:
        raise InputError(
            f"spacing must be a multiple of 1/{SAMPLES_PER_PIXEL} px dividing "
            f"the patch; got {spacing!r}"
        )
    f = np.fft.fftfreq(n, d=1 / SAMPLES_PER_PIXEL)  # [cycles/px]
    radius = np.hypot(*np.meshgrid(f, f)) * spacing * 2  # the pupil's edge: 1/(2·spacing)
    inner = 1 - PUPIL_TAPER
    iris = np.where(
        radius <= inner,
        1.0,
        np.where(radius < 1, 0.5 * (1 + np.cos(np.pi * (radius - inner) / PUPIL_TAPER)), 0.0),
    )
    # the defocus's phase at the pupil's edge, in units of the blur: π/4 · D²δ/λ, with
    # D/λ = 1/(spacing·Δ) and blur = Dδ/Δ
    spectrum = iris * np.exp(1j * np.pi / 4 * blur / spacing * radius**2)
    count = n // step
    i, j = np.meshgrid(np.arange(count), np.arange(count), indexing="ij")
    codes = coded_look_codes(looks)
    centres = ((np.arange(pixels * supersample) + 0.5) * SAMPLES_PER_PIXEL / supersample).astype(
        int
    )
    spread = []
    for seed in range(seeds):
        rng = np.random.default_rng(seed)
        offset = rng.integers(0, step, 2)
        base = rng.uniform(0, 2 * np.pi, (count, count))
        total = np.zeros((pixels, pixels))
        for look in range(looks):
            if codes is None:
                phase = base if look == 0 else rng.uniform(0, 2 * np.pi, (count, count))
            else:
                k1, k2 = divmod(codes[look][0], codes[look][1])
                phase = base + 2 * np.pi * (k1 * j + k2 * i) / codes[look][1]
            comb = np.zeros((n, n), complex)
            comb[offset[0] :: step, offset[1] :: step] = np.exp(1j * phase)
            field = np.fft.ifft2(np.fft.fft2(comb) * spectrum)
            fine = np.abs(field[np.ix_(centres, centres)]) ** 2
            total += downsample(fine, supersample)
        spread.append(total.var() / total.mean() ** 2)
    return float(np.mean(spread))
