"""Tolerances shared by the tests, with the reason for each (pyvkfft's accuracy.py in spirit)."""

import numpy as np

# complex64 device pipelines against float64 NumPy: ~1e-7 per FFT pass, a few passes
FLOAT32_PIPELINE = 1e-5
# float32 kernels doing O(N) sums per output (direct RS, resampling matrix products)
FLOAT32_SUM = 1e-5
# band-limited ASM against direct Rayleigh-Sommerfeld (the bounds; measured with the
# rolled-off band edge: 3e-4, 5e-5, 2.6e-3 and 1e-5, see test_angular_spectrum)
ASM_VS_RS = {"fresnel 1-5": 5e-3, "fresnel 0.25": 1e-2, "fresnel 0.25 padded 4x": 3e-3}
# paraxial Gaussian beam formula vs exact propagation, w0 >> λ: (λ/(π w0))² ~ 1e-5
GAUSSIAN_BEAM = 1e-4
# spectrum rotation with linear interpolation (Delen & Hooker), measured on a tilted beam
TILT_PADDED_2 = 1.5e-2
TILT_PADDED_4 = 4e-3  # measured 3.0e-3 (20° about y)
TILT_PADDED_4_TWO_AXES = 7e-3  # measured 5.2e-3 (-12° about x, 8° about y): 2-D interpolation


def rel_err(a, ref) -> float:
    """Relative complex error ||a - ref|| / ||ref|| in float64."""
    a, ref = np.asarray(a, np.complex128), np.asarray(ref, np.complex128)
    return float(np.linalg.norm(a - ref) / np.linalg.norm(ref))
# point-source sum (segment recurrence, phase error <= 5e-5 rad per pair) vs float64 NumPy
POINT_SUM = 1e-4
# wavefront recording planes vs the direct sum: the soft cone rim is defined on different
# planes (measured 5e-3 for points 0.1-0.2 m from a 2 mm hologram at 8 µm pitch)
WRP_VS_DIRECT = 1e-2
# a flat coherent triangle: band-limited primitive pipeline vs its samples as point sources
# (the two discretisations differ at the band edge; measured 1.6e-2)
PRIMITIVE_VS_POINTS = 3e-2
# image generation (Sect. VII)
PIXEL_POSITION = 0.5        # px, the bound for a point through a pinhole
AIRY_RADIUS = 0.05          # first zero vs 1.22 λ/D (measured ~2 % with 4 spectrum samples/λ/D)
DEFOCUS_DIAMETER = 0.10     # blur disc vs D·|1/r - 1/f| (geometric optics)
DEPTH_SINGLE_POINT = 5e-3   # two-wavelength depth vs the true planar depth (measured 2e-5)
ALIAS_ENERGY = 1e-2         # energy above the new Nyquist, against a point-sampled raster's
SPECKLE_SQRT_N = 0.3        # contrast ratio of 1 vs N renders against √N (finite-N scatter)
