"""The images leave the device folded to the camera's pixels (optics/imaging.py
PupilImage.fold): each pixel's mean |A|² and the depth pair's mean u1·conj(u2) over its s×s
fine pixels, read from every look's spectra at once, against the images read one by one
(PupilImage.image, each pixel's bins from the camera's direction cosines) folded by float64
NumPy."""

import numpy as np
import pytest
from accuracy import rel_err

from holo_core.opencl import get_runtime
from holo_core.optics.imaging import PupilImage
from holo_core.scene.camera import Camera, look_at

FOLD = 1e-5  # float32 sums against float64 and the kernel's own rays: measured 1e-7


@pytest.mark.parametrize("s", [1, 2, 3])
def test_the_pixels_are_the_means_of_their_fine_pixels(rng, s):
    rt = get_runtime()
    shape, bin_ = (24, 30), 4e-3
    fine = Camera(
        matrix_world=look_at((0, 0, 1), (0.1, 0, 0), up=(0, 1, 0)),
        lens=50,
        sensor_width=36,
        resolution=(10 * s, 6 * s),
        shift_x=0.05,
    )
    imager = PupilImage(rt, shape, bin=bin_, camera=fine, centre=(0.01, -0.02))
    looks, names = 2, [4, 5, 6, 7]
    optics = {
        c: ((1e-3 + 1e-4 * m, 1.1e-3), 2e6 * (1 + 0.1 * m), 0.5 + m) for m, c in enumerate(names)
    }
    pupils = (
        rng.normal(size=(looks * 4,) + shape) + 1j * rng.normal(size=(looks * 4,) + shape)
    ).astype(np.complex64)
    kw = {"diameter": 0.02, "focus": 0.7}
    folded = imager.fold(
        rt.to_device(pupils), optics, same=[4, 6], partner=7, supersample=s, keep_fine=True, **kw
    )

    def means(a):
        return a.reshape(6, s, 10, s).mean((1, 3))

    for look in range(looks):
        images = {
            c: imager.image(
                rt.to_device(pupils[look * 4 + m]),
                pitch=optics[c][0],
                lens_k=optics[c][1],
                scale=optics[c][2],
                **kw,
            )
            for m, c in enumerate(names)
        }
        got = folded[look]
        for c, a in images.items():
            assert got.power[c].shape == (6, 10)
            assert rel_err(got.power[c], means(np.abs(a) ** 2)) < FOLD, (look, c)
            assert rel_err(got.fine[c], a) < FOLD, (look, c)
        want = means((images[4] + images[6]) * np.conj(images[7]))
        assert rel_err(got.cross, want) < FOLD, look
    alone = imager.fold(
        rt.to_device(pupils[:1]), {4: optics[4]}, same=[4], partner=None, supersample=s, **kw
    )
    assert len(alone) == 1 and alone[0].cross is None and alone[0].fine is None
    assert rel_err(alone[0].power[4], folded[0].power[4]) < 1e-6
