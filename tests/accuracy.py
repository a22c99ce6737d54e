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
# spectrum rotation, 6-tap ES interpolation with deapodization, on tilted Gaussian beams:
# measured 4.0e-5 (20° about y, padding 2 and 4), 1.5e-5 (two axes), 2.5e-5 (placed plane);
# linear interpolation gave 1.2e-2, 3.0e-3 and 5.2e-3
TILT = 1e-4

# point-source sum (segment recurrence, phase error <= 5e-5 rad per pair) vs float64 NumPy
POINT_SUM = 1e-4
# wavefront recording planes vs the direct sum: the soft cone rim is defined on different
# planes (measured 5e-3 for points 0.1-0.2 m from a 2 mm hologram at 8 µm pitch)
WRP_VS_DIRECT = 1e-2
# a triangle, primitive pipeline (spectrum interpolation + band-limited ASM) vs its samples as
# Rayleigh-Sommerfeld point sources, 96² hologram: measured 9.8e-4 flat and coherent, 6.4e-3
# tilted 15° and diffuse. The rest is the source model at the grid's Nyquist edge: a sampled
# field whose spectrum stops there (pipeline) vs a comb of points whose spectrum goes on
# (reference), worst for diffuse fields, which fill the band. Linear interpolation of the
# rotated spectrum, before, gave 1.8e-2 flat and 0.1-0.25 tilted.
PRIMITIVE_VS_POINTS = 1e-2
# image generation (Sect. VII)
PIXEL_POSITION = 0.5  # px, the bound for a point through a pinhole
AIRY_RADIUS = 0.05  # first zero vs 1.22 λ/D (measured ~2 % with 4 spectrum samples/λ/D)
DEFOCUS_DIAMETER = 0.10  # blur disc vs D·|1/r - 1/f| (geometric optics)
DEPTH_SINGLE_POINT = 5e-3  # two-wavelength depth vs the true planar depth (measured 2e-5)
ALIAS_ENERGY = 1e-2  # energy above the new Nyquist, against a point-sampled raster's
SPECKLE_SQRT_N = 0.3  # contrast ratio of 1 vs N renders against √N (finite-N scatter)

# a transfer function made on the device (float64, or float32 with the split product) vs the
# float64 host one: complex64 rounding and cexpi's 1e-7 (measured 3e-7 in float64; the split
# route 5.4e-7 rad of phase at k·z = 7.9e6 rad, 1.1e-6 in the band's float32 roll-off weight)
TRANSFER_ON_DEVICE = 2e-6
# the dot-product test of a propagation and its adjoint, complex64 on 48 x 64 (float32 sums
# of a few FFTs; measured below 1e-7)
ADJOINT = 1e-6
# the dot-product test of a propagation and its adjoint, complex64 on 48 x 64 (float32 sums
# of a few FFTs; measured 1.5e-9 to 5.2e-9 relative to |A·x|·|y|)
ADJOINT = 1e-6
# the sideband filter of an off-axis hologram vs the known object wave inside its band (the
# issue's bound; measured 3e-8 to 1e-6 with the carrier known)
SIDEBAND = 1e-2
# ... and with a carrier found in the spectrum: the +1 order's peak is pulled by the object's own
# low frequencies (5e-3 bin for a 0.1 diffuse part), a tilt of ~1e-2 rad across the field
SIDEBAND_FOUND = 3e-2


def rel_err(a, ref) -> float:
    """Relative complex error ||a - ref|| / ||ref|| in float64."""
    a, ref = np.asarray(a, np.complex128), np.asarray(ref, np.complex128)
    return float(np.linalg.norm(a - ref) / np.linalg.norm(ref))


# the zone sum (per-tile exact phase, row recurrence, the window exact in its rim, the
# visibility linear along 32-sample segments) vs float64 NumPy: measured 7e-6 with a smooth
# visibility, 1e-3 with a table of random values (kinks every grid cell)
ZONE_SUM = 1e-4
ZONE_SUM_ROUGH_VISIBILITY = 3e-3
# the physical field re-modulated from a carrier plate's samples (a 64-tap Kaiser-windowed
# sinc, ripple 1.8e-6 over the zone's own band) against the float64 direct sum: the zone sum's
# own float32 error (measured 9.2e-6 to 1.0e-5 where the samples hold their band)
PHYSICAL_FIELD = 3e-5
