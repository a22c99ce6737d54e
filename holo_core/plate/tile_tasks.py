"""The tasks of a tiled recording (:mod:`.tiles`), one a tile, as a Dask worker runs them: the
tile's sums written with its record into the stores that lack it, nothing written into a
store that now holds another recording.
"""

from __future__ import annotations

import numpy as np

from ..io import store
from ..opencl import get_runtime
from ..validate import InputError
from .point_sources import point_wave, sampling_grid
from .recording import PlateRecording


def record_tile(points, spec: dict, i: int, j: int) -> tuple[int, int]:
    """One task: tile (i, j) of the store ``spec`` names, from the emitters ``points``
    (positions, amplitudes) whose cones reach it, written with its record. A store that now
    holds another recording (replaced while this task waited) is left alone."""
    pos, amp = points
    (plate,) = _still_ours(spec, i, j).values()
    info, tile = plate.info, plate.tile
    shape, pitch, band = plate.shape, info.pitch, info.band or None
    r0, r1, c0, c1 = store.tile_window(shape, tile, i, j)
    # the tile's centre in the plate's frame: its samples lie where the whole plate's do
    centre = np.array(
        [
            ((c0 + c1 - 1) / 2 - (shape[1] - 1) / 2) * pitch,
            ((r0 + r1 - 1) / 2 - (shape[0] - 1) / 2) * pitch,
            0.0,
        ]
    )
    half = np.array([(c1 - c0) / 2 * pitch, (r1 - r0) / 2 * pitch])
    waves = np.zeros((plate.count, r1 - r0, c1 - c0), np.complex64)
    groups = {}
    for c, lam in enumerate(info.wavelengths):
        groups.setdefault(lam, []).append(c)
    for lam, chans in groups.items():
        cone = sampling_grid(shape, lam, pitch, band).cone
        reach = np.abs(pos[:, 2]) * cone + pitch
        gap = np.maximum(np.abs(pos[:, :2] - centre[:2]) - half, 0)
        near = (gap**2).sum(1) <= reach**2
        if near.any():
            waves[chans] = point_wave(
                pos[near] - centre,
                amp[near][:, chans],
                wavelength=lam,
                pitch=pitch,
                shape=(r1 - r0, c1 - c0),
                band=band,
                method=plate.recording["parts"]["method"],
            )
    plate.write_tile(i, j, waves)
    return i, j


def record_plate_tile(job: PlateRecording, spec: dict, i: int, j: int) -> tuple[int, int]:
    """One task: tile (i, j) of the stores ``spec`` names (one a look), the zone sum of
    ``job``'s emitters over its block, every look at once, each look's channels written into
    its store with its record (the stores of ``spec``'s "looks": those that lack the tile).
    The emitters go onto this worker's device once per recording (kept in its runtime's cache
    for the next tiles). Stores that now hold another recording (replaced while this task
    waited) are left alone."""
    plates = _still_ours(spec, i, j)
    first = next(iter(plates.values()))
    r0, r1, c0, c1 = store.tile_window(first.shape, first.tile, i, j)
    rt = get_runtime()
    key = ("zone-sums", *spec["recordings"])
    if key not in rt.cache:
        for other in [k for k in rt.cache if isinstance(k, tuple) and k[0] == "zone-sums"]:
            del rt.cache[other]  # an earlier recording's emitters: their device memory freed
        rt.cache[key] = job.sums(rt)
    samples = job.region(rt.cache[key], r0, c0, r1 - r0, c1 - c0)
    for look, plate in plates.items():
        plate.write_tile(i, j, samples[job.look_channels(look)])
    return i, j


def _still_ours(spec: dict, i: int, j: int) -> dict:
    """{look: its store} of the looks ``spec`` writes (its "looks", default all; their
    metadata checked, no record read), or :class:`InputError` if one now holds another
    recording than ``spec``'s (none is then written)."""
    plates = {}
    for look in spec.get("looks", range(len(spec["urls"]))):
        url, digest = spec["urls"][look], spec["recordings"][look]
        plate = store.read_store(url, records=False)
        if plate.recording["digest"] != digest:
            raise InputError(
                f"{url}: now holds another recording; tile ({i}, {j}) of "
                f"recording {digest[:12]} is not written"
            )
        plates[look] = plate
    return plates
