import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


@pytest.fixture(scope="session")
def rt():
    from holo_core.opencl import get_runtime

    return get_runtime()


@pytest.fixture(scope="module")
def point_hologram():
    """The point behind a small plate of :mod:`pinhole`."""
    import pinhole

    return pinhole.record()


@pytest.fixture
def small_disk(tmp_path):
    """A 1 MiB file system of its own (a tmpfs: the test must run as root, else it is skipped)."""
    from mounts import small_disk

    with small_disk(tmp_path / "disk") as disk:
        yield disk
