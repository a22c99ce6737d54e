"""Holo: holographic scene representation and wave-based image synthesis.

Conventions (README): SI metres and radians; the hologram plane is z = 0 and light travels
towards +z; fields are exp(+ikr) waves (time dependence exp(-iωt)); arrays are [row, col] =
[y, x] with column j at x = (j - (W-1)/2)·pitch.
"""

__version__ = "0.1.0"

_API = {"record_hologram": ".record", "Plate": ".record", "render_view": ".render",
        "write_view": ".render", "Camera": ".camera", "look_at": ".camera",
        "read_hologram": ".hologram_io", "write_hologram": ".hologram_io",
        "InputError": ".validate"}


def __getattr__(name):  # the top-level API, imported on first use (keeps `import` light)
    if name not in _API:
        raise AttributeError(f"module 'holo_core' has no attribute {name!r}")
    from importlib import import_module
    return getattr(import_module(_API[name], __name__), name)
