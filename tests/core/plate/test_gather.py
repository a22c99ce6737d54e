"""The gather of a carrier plate's decimated samples onto the pupil's plane waves
(holo_core.plate.gather): its depth layers converge as they get finer."""

import math

import numpy as np
from accuracy import rel_err
from plate_scene import SMALL, camera

from holo_core.plate import gather
from holo_core.plate.view import render_view


def test_views_in_finer_depth_layers_converge(carrier_plate, monkeypatch):
    """The gather's depth layers (spaced in 1/z so that each one's curvature errs by at most
    LAYER_PHASE at the pupil's rim), each spread, transformed and curved by its own distance
    on the device, converge as they get finer: against a thousandth of LAYER_PHASE (35
    layers here), the default's one layer (a quarter wave at the rim for the samples farthest
    from it) is within 1e-2 and a three-hundredth's (11 layers)
    less than half as far (the error falls as the phase error, to first order: 3.2e-3 and
    8.2e-4 here); their alpha likewise (1.5e-2 and 2e-3 at most: a pixel whose alpha lies
    that near 0.5 may cross it)."""
    cam = camera("left", SMALL)
    made, counts, views = gather.Gather._layers, [], []

    def layers(self, wavelength):
        out = made(self, wavelength)
        counts.append(len(out))
        return out

    monkeypatch.setattr(gather.Gather, "_layers", layers)
    for share in (1, 300, 1000):
        monkeypatch.setattr(gather, "LAYER_PHASE", math.pi / 2 / share)
        views.append(render_view(carrier_plate, cam, supersample=2))
    assert counts[0] == 1 and counts[-1] > 10, counts
    one, fine, finer = views
    far = rel_err(one.radiance, finer.radiance)
    assert far < 1e-2 and rel_err(fine.radiance, finer.radiance) < 0.5 * far
    edge = [np.abs(v.alpha - finer.alpha).max() for v in (one, fine)]
    flips = [int(((v.alpha > 0.5) != (finer.alpha > 0.5)).sum()) for v in (one, fine)]
    print(f"alpha apart at most {np.round(edge, 5)}, pixels across 0.5 {flips}")
    assert edge[0] < 2e-2 and edge[1] < 0.5 * edge[0], edge
