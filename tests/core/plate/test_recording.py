"""A plate of meshes prepared for its sums (holo_core.plate.recording): its samples do not
depend on the camera once its zone is given, it is stored complex (an intensity encoding or a
point sum's resolution are refused by name), and a zone sum that comes back not finite records
nothing."""

import numpy as np
import pytest
from huge import huge_mesh, never
from plate_scene import PLATE, camera, meshes

from holo_core.plate.looks import record_looks, record_plate
from holo_core.plate.record import record_hologram
from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import Plate, ViewingZone
from holo_core.validate import InputError


def test_camera_settings_never_change_the_plate():
    """With its zone given (where and for which pupil and pixels), the plate does not depend
    on the camera: another position inside the zone, focus, f-stop and resolution record the
    same samples, bit for bit."""
    zone = ViewingZone(
        centre=(0, 0, 0.3), half_extents=(0.04, 0.04, 0.03), pupil=0.05 / 2.8, pixel=4.5e-3
    )
    plate = Plate(matrix_world=np.eye(4), width=0.02, height=0.02, zone=zone)
    square = _square(0.01, -0.3)
    a = record_hologram(square, plate=plate, camera=camera("centre", 0.1))
    b = record_hologram(
        square,
        plate=plate,
        camera=Camera(
            matrix_world=look_at((0.01, 0.01, 0.29), (0, 0, -0.3)),
            lens=35,
            fstop=8,
            focus_distance=1.0,
            resolution=(33, 17),
        ),
    )
    assert a.object_wave.tobytes() == b.object_wave.tobytes()
    assert a.zone is zone and a.encoding == "complex" and a.intensity is None
    assert a.carrier.centre == zone.centre


def test_a_plate_of_meshes_is_complex_and_its_resolution_the_zones():
    """A plate of meshes records the object wave against its carrier (a display's intensity
    pattern is made from it); a resolution of samples is a point sum's, refused by name."""
    plate = Plate(matrix_world=np.eye(4), width=0.03, height=0.03)
    with pytest.raises(InputError, match="encoding must be 'complex' for a plate of meshes"):
        record_plate(
            _square(0.012, -0.3), plate=plate, camera=camera("centre", 0.1), encoding="intensity"
        )
    with pytest.raises(InputError, match="resolution applies to point sums"):
        record_hologram(
            _square(0.012, -0.3), plate=plate, camera=camera("centre", 0.1), resolution=256
        )


def _square(size, z, texture=None):
    h = size / 2
    v = np.array([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]])
    return Mesh(
        vertices=v,
        triangles=np.array([[0, 1, 2], [0, 2, 3]]),
        colours=None if texture is not None else np.full((4, 3), 0.5),
        uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]) if texture is not None else None,
        texture=texture,
    )


SCALE = 0.25  # the plate scene's camera at 160x90: a plate of about 640x640 samples


def test_a_zone_sum_that_comes_back_not_finite_records_nothing(monkeypatch):
    """A device whose zone sum comes back with NaN (its arithmetic failed) stops the
    recording with the rows where it happened; no plate is returned, so none is written."""
    from holo_core.plate import zone_sum

    summed = zone_sum.ZoneSum.on_device

    def failed(self, row0, *args):
        out = summed(self, row0, *args)
        if row0 >= 256:
            out.fill(np.complex64(np.nan))
        return out

    monkeypatch.setattr(zone_sum.ZoneSum, "on_device", failed)
    kw = {"plate": PLATE, "camera": camera("centre", SCALE), "zone_margin": 0.025}
    with pytest.raises(RuntimeError, match="non-finite samples in rows 256-"):
        record_looks(meshes(), looks=2, seed=4, **kw)


def test_ten_million_triangles_are_refused_by_the_plate_recording(monkeypatch):
    """Moving a mesh onto the plate is counted before the emitters are found: ten million
    triangles against a 2 GiB budget are refused with the memory they need."""
    import holo_core.plate.recording as recording

    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "2G")
    monkeypatch.setattr(recording, "zone_emitters", never)
    with pytest.raises(
        InputError,
        match=r"moving 10000000 triangles onto the plate needs "
        r"\d\.\d+ GiB",
    ):
        record_plate(
            huge_mesh(5 * 10**6), plate=Plate(matrix_world=np.eye(4), width=0.05, height=0.05)
        )


def test_a_mesh_whose_emitters_cannot_be_found_in_memory_is_refused_first(rng, monkeypatch):
    """Random triangles through each other cross every ray of the zone many times over (10⁷
    vertices held 4.75 GB and ran past 150 s after the memory estimate passed them): counted
    before the work, they are refused by their crossings; a cube of one look in the same
    memory is not (two looks of its plate, 0.2 GiB, would be refused by their size)."""
    from holo_core.plate.recording import plate_plan
    from holo_core.scene.camera import Camera, look_at

    plate = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
    camera = Camera(
        matrix_world=look_at((0, 0, 0.3), (0, 0, -0.33)),
        resolution=(160, 90),
        fstop=2.8,
        focus_distance=0.63,
    )
    v = rng.uniform([-0.03, -0.03, -0.36], [0.03, 0.03, -0.3], (30_000, 3))
    noise = Mesh(vertices=v, triangles=rng.integers(0, len(v), (10_000, 3)))
    corners = np.array(
        [[x, y, z] for x in (-0.03, 0.03) for y in (-0.03, 0.03) for z in (-0.36, -0.3)]
    )
    cube = Mesh(
        vertices=corners,
        triangles=[
            [0, 1, 3],
            [0, 3, 2],
            [4, 6, 7],
            [4, 7, 5],
            [0, 4, 5],
            [0, 5, 1],
            [2, 3, 7],
            [2, 7, 6],
            [0, 2, 6],
            [0, 6, 4],
            [1, 5, 7],
            [1, 7, 3],
        ],
    )
    monkeypatch.setenv("HOLO_MEMORY_LIMIT", "200M")  # a step may take memory.SHARE of it
    plate_plan(cube, plate=plate, camera=camera, looks=1)
    with pytest.raises(
        InputError,
        match=r"finding the emitters of 10000 triangles \(1\.\d+e\+06 "
        r"crossings of the zone's rays.* needs 0\.\d+ GiB of "
        r"memory",
    ):
        plate_plan(noise, plate=plate, camera=camera, looks=1)
