"""The plan in plain words (holo_core.plate.plan_summary): the verdict first, then the time,
the plate, the zone, the wavelength, the emitters, disk and a view's reads, each figure the
plan's own; a blurred view says what makes it sharp and a camera outside the zone is warned."""

import numpy as np

from holo_core.plate.plan import plan, plan_view
from holo_core.plate.plan_summary import summary
from holo_core.scene.plate import ViewingZone

BOX = np.array([[-0.02, -0.015, -0.33], [0.025, 0.02, -0.28]])
PIXEL = 0.036 / 640 / 0.05  # 50 mm, 36 mm sensor, 640 px [rad]
PUPIL = 0.05 / 2.8  # [m]


def words(position, pixel=PIXEL, resolution=(640, 360)):
    zone = ViewingZone.around((0, 0, 0.3), PUPIL, 0.01, pixel=PIXEL)
    p = plan((0.1, 0.1), BOX, zone=zone, pixel_angle=PIXEL)
    v = plan_view(p, position=position, pixel_angle=pixel, pupil=PUPIL, resolution=resolution)
    said = summary(
        p,
        v,
        lens="50 mm f/2.8",
        resolution=resolution,
        plate_size=(0.1, 0.1),
        camera=position,
        load_average=0,
    )
    return p, v, said


def test_the_verdict_comes_first_and_the_figures_are_the_plans():
    p, v, said = words((0, 0, 0.3))
    assert [line.split()[0] for line in said] == [
        "verdict",
        "time",
        "plate",
        "zone",
        "wavelength",
        "emitters",
        "disk",
        "per",
    ]
    assert said[0].endswith("are sharp"), said[0]
    rows, cols = p.shape
    assert f"{cols} x {rows} samples" in said[2], said[2]
    assert f"{p.wavelength * 1e6:.4g} µm" in said[4] and f"{p.emitters:,}" in said[5]
    assert f"reads {v.window / 1e6:.3g} Mpx" in said[7], said[7]


def test_a_blurred_view_says_what_makes_it_sharp_and_outside_the_zone_is_warned():
    _, v, said = words((0.0, 0.0, 0.3), pixel=PIXEL / 3, resolution=(1920, 1080))
    assert not v.sharp and "blurred" in said[0] and "Camera mode" in said[0], said[0]
    _, v, said = words((0.2, 0.0, 0.3))
    assert v.outside_zone > 0 and said[-1].startswith("warning"), said[-1]
    assert f"{v.outside_zone * 1e3:.3g} mm beyond the zone" in said[-1]
