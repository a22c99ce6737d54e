
import os
import subprocess

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
    """A 1 MiB file system of its own, a folder on it (a tmpfs: the test must run as root)."""
    mount = tmp_path / "disk"
    mount.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs",
                                            str(mount)], capture_output=True).returncode:
        pytest.skip("mounting a small file system needs root")
    try:
        yield mount
    finally:
        subprocess.run(["umount", str(mount)], check=True)

