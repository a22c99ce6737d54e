"""Holo: holographic scene representation and wave-based image synthesis.

Conventions (README): SI metres and radians; the hologram plane is z = 0 and light travels
towards +z; fields are exp(+ikr) waves (time dependence exp(-iωt)); arrays are [row, col] =
[y, x] with column j at x = (j - (W-1)/2)·pitch.
"""

__version__ = "0.1.0"

_API = {"Camera": ".scene", "look_at": ".scene", "Plate": ".scene", "Hologram": ".scene",
        "Mesh": ".scene", "Pupil": ".optics", "record_hologram": ".plate",
        "record_points": ".plate", "reconstruct": ".plate", "render_view": ".plate",
        "render_camera": ".camera", "RenderResult": ".view", "write_view": ".io.view",
        "read_hologram": ".io.hologram", "write_hologram": ".io.hologram",
        "read_mesh": ".io.mesh", "InputError": ".validate"}


def __getattr__(name):  # the top-level API, imported on first use (keeps `import` light)
    if name not in _API:
        raise AttributeError(f"module 'holo_core' has no attribute {name!r}")
    from importlib import import_module
    return getattr(import_module(_API[name], __name__), name)


def __dir__():
    return sorted([*globals(), *_API])
