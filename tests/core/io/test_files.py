"""A store's address: a local path, ``file://`` and ``local://`` are one local folder (its
links never followed, its lock an flock); another fsspec file system with folders is
recorded into as it is, its folders made before a file is put in them."""

import numpy as np
import pytest

zarr = pytest.importorskip("zarr")
fsspec = pytest.importorskip("fsspec")

from fsspec.implementations.local import LocalFileSystem  # noqa: E402

from holo_core.io import store  # noqa: E402
from holo_core.io.digests import digest_of  # noqa: E402
from holo_core.io.files import Files, StoreError, check_output  # noqa: E402
from holo_core.io.tiled_wave import open_plate  # noqa: E402
from holo_core.scene.hologram import HologramInfo  # noqa: E402

SHAPE, TILE = (128, 128), 64
INFO = HologramInfo(shape=SHAPE, encoding="complex", wavelengths=(633e-9,), pitch=8e-6)
RECORDING = {"digest": digest_of({"scene": "b"}), "parts": {"scene": "b"}}
WAVE = (np.arange(SHAPE[0] * SHAPE[1]).reshape(1, *SHAPE) * (1 + 1j)).astype(np.complex64)


def record(url):
    with store.recording_into(check_output(url), INFO, TILE, RECORDING) as plate:
        for i, j in np.ndindex(*store.tile_grid(SHAPE, TILE)):
            r0, r1, c0, c1 = store.tile_window(SHAPE, TILE, i, j)
            plate.write_tile(i, j, WAVE[:, r0:r1, c0:c1])


@pytest.mark.parametrize("scheme", ["local://", "file://"])
def test_a_local_url_is_recorded_as_its_folder(tmp_path, scheme):
    """``local://`` (fsspec's name of the local file system) failed on the first chunk, its
    folder never made; it is the folder itself, written and read as a path is."""
    folder = tmp_path / "p.zarr"
    url = f"{scheme}{folder}"
    assert Files(url).local == folder
    record(url)
    assert (folder / "holo.lock").is_file()  # the folder's lock, not a URL's lock file
    assert np.array_equal(open_plate(url).object_wave[...], WAVE)
    assert np.array_equal(open_plate(folder).object_wave[...], WAVE)


class _Folders(LocalFileSystem):
    """A file system with folders under a protocol of its own (as sftp://, smb:// or an
    NFS gateway are): a file is put only into a folder that exists."""

    protocol = ("holo-folders",)
    root_marker = "/"

    @classmethod
    def _strip_protocol(cls, path):
        return LocalFileSystem._strip_protocol(str(path).replace(f"{cls.protocol[0]}://", "", 1))


def test_a_file_system_with_folders_is_recorded_into(tmp_path):
    fsspec.register_implementation("holo-folders", _Folders, clobber=True)
    url = f"holo-folders://{tmp_path}/p.zarr"
    assert Files(url).local is None  # not known to be local: written as a URL's files
    record(url)
    assert not (tmp_path / "p.zarr" / "holo.lock").exists()  # a URL's lock: gone at the end
    assert np.array_equal(open_plate(url).object_wave[...], WAVE)


class _Unreachable(_Folders):
    protocol = ("holo-unreachable",)

    def makedirs(self, path, exist_ok=False):
        raise ConnectionRefusedError(111, "Connection refused")


def test_a_file_system_that_does_not_answer_is_refused_before_the_work(tmp_path):
    fsspec.register_implementation("holo-unreachable", _Unreachable, clobber=True)
    url = f"holo-unreachable://{tmp_path}/p.zarr"
    with pytest.raises(
        StoreError,
        match=rf"^{url}: cannot be reached or written "
        rf"\(ConnectionRefusedError: .*Connection refused",
    ):
        check_output(url)
