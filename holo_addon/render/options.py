"""What the worker takes from the add-on's preferences: device, memory limit, cache, the
runtime's packages, the Dask scheduler of tiled plates."""

from __future__ import annotations

from pathlib import Path

import bpy

# The add-on's module name: "bl_ext.<repository>.holo" when installed as an extension (the
# package above holo_addon), "holo_addon" from a source tree
ADDON = ".".join(__package__.split(".")[:-2]) or __package__.split(".")[0]


def runtime_prefix() -> Path:
    """The folder packages installed on demand go to (pip's ``--prefix``)."""
    try:
        return Path(bpy.utils.extension_path_user(ADDON, path="runtime", create=True))
    except (ValueError, AttributeError):  # not installed as an extension (source tree, tests)
        return Path(bpy.utils.user_resource("SCRIPTS", path="holo_runtime", create=True))


def runtime_paths() -> list[str]:
    """site-packages folders under :func:`runtime_prefix` (the worker's extra search path)."""
    return [str(p) for p in sorted(runtime_prefix().glob("lib/python*/site-packages"))]


def addon_preferences():
    addon = bpy.context.preferences.addons.get(ADDON)
    return addon.preferences if addon is not None else None


def device() -> str:
    """The device the user chose ("" for automatic)."""
    prefs = addon_preferences()
    return prefs.device.strip() if prefs is not None else ""


def worker_options() -> dict:
    """What :class:`holo_core.worker.Worker` takes from the preferences."""
    prefs = addon_preferences()
    limit = prefs.memory_limit if prefs is not None else 0.0
    cache = bpy.path.abspath(prefs.cache_dir) if prefs is not None and prefs.cache_dir else None
    return {
        "paths": runtime_paths(),
        "device": device() or None,
        "memory_limit": f"{limit}G" if limit > 0 else None,
        "cache_dir": cache,
    }


def scheduler() -> str | None:
    """The Dask scheduler's address the user chose for tiled plates (None: the environment's
    DASK_SCHEDULER_ADDRESS, else a local cluster)."""
    prefs = addon_preferences()
    address = prefs.scheduler.strip() if prefs is not None else ""
    return address or None
