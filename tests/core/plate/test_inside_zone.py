"""Where a pupil lies against a plate's zone, in words (holo_core.plate.inside_zone): each way
it reaches beyond the zone named with its distance (a pupil's rim counts sideways, not in
depth), the total as the zone measures it, metres past 10 cm."""

import pytest

from holo_core.plate.inside_zone import beyond_words
from holo_core.scene.plate import ViewingZone

ZONE = ViewingZone(centre=(0.0, 0.0, 0.3), half_extents=(0.05, 0.02, 0.01), pupil=0.01)


@pytest.mark.parametrize(
    "position, pupil, ways",
    [
        ((0.07, 0.0, 0.3), 0.0, ["20 mm past its +x (right) side"]),
        ((-0.06, 0.0, 0.3), 0.01, ["15 mm past its -x (left) side"]),
        ((0.0, -0.03, 0.3), 0.0, ["10 mm past its -y (down) side"]),
        ((0.0, 0.0, 0.25), 0.01, ["40 mm nearer the plate"]),
        ((0.0, 0.0, 0.61), 0.0, ["0.3 m farther from the plate"]),
        ((0.07, 0.03, 0.3), 0.0, ["+x (right) side", "10 mm past its +y (up) side"]),
    ],
)
def test_each_way_beyond_the_zone_is_named_with_its_distance(position, pupil, ways):
    said = beyond_words(ZONE, position, pupil)
    total = ZONE.distance_outside(position, pupil / 2)
    assert total > 0
    length = f"{total * 1e3:.3g} mm" if total < 0.1 else f"{total:.3g} m"
    assert said.startswith(f"it reaches {length} beyond the zone, "), said
    for way in ways:
        assert way in said, (way, said)
    assert said.count(" and ") == len(ways) - 1, said
