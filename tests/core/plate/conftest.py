import numpy as np
import pytest

from holo_core.plate.zone_sum import ZoneEmitters


@pytest.fixture(scope="module")
def scheduler():
    """One local Dask cluster for the module, reached by its address as a remote one would
    be."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address="127.0.0.1:0"
    ) as cluster:
        yield cluster.scheduler_address


@pytest.fixture(scope="module")
def emitters():
    """40 emitters 0.25-0.35 m behind the plate, seen from the whole zone."""
    rng = np.random.default_rng(1)
    n = 40
    pos = np.stack(
        [rng.uniform(-0.02, 0.02, n), rng.uniform(-0.02, 0.02, n), rng.uniform(-0.35, -0.25, n)], 1
    )
    return ZoneEmitters(
        position=pos,
        amplitude=rng.normal(size=(n, 1)) + 1j * rng.normal(size=(n, 1)),
        visibility=np.full(n, -1, np.int32),
        table=np.zeros((0, 3, 5), np.uint8),
        grid=((-0.03, 0.015), (-0.02, 0.01)),
    )


@pytest.fixture(scope="session")
def carrier_plate():
    """The plate scene's plate against its carrier, for the cameras at SMALL (160x90), its zone 25 mm beyond the pupil."""
    from plate_scene import PLATE, SMALL, camera, meshes

    from holo_core.plate.looks import record_plate

    return record_plate(meshes(), plate=PLATE, camera=camera("centre", SMALL), zone_margin=0.025)
