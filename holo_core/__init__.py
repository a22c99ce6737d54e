"""Holo: holographic scene representation and wave-based image synthesis.

Conventions (README): SI metres and radians; the hologram plane is z = 0 and light travels
towards +z; fields are exp(+ikr) waves (time dependence exp(-iωt)); arrays are [row, col] =
[y, x] with column j at x = (j - (W-1)/2)·pitch.
"""

from .lazy import lazy_names

__version__ = "0.2.0"

_API = {"Camera": ".scene", "look_at": ".scene", "Plate": ".scene", "ViewingZone": ".scene",
        "Hologram": ".scene",
        "Mesh": ".scene", "Pupil": ".optics", "record_hologram": ".plate",
        "record_points": ".plate", "reconstruct": ".plate", "render_view": ".plate",
        "physical_field": ".plate", "sideband": ".acquired", "find_carrier": ".acquired",
        "render_camera": ".camera", "RenderResult": ".view", "write_view": ".io.view",
        "read_hologram": ".io.hologram", "write_hologram": ".io.hologram",
        "import_acquired": ".acquired", "read_acquired": ".io.acquired",
        "write_acquired": ".io.acquired", "object_hologram": ".acquired",
        "autofocus": ".acquired", "unwrap": ".acquired",
        "read_mesh": ".io.mesh", "InputError": ".validate",
        "angular_spectrum": ".propagation", "fresnel": ".propagation",
        "fraunhofer": ".propagation", "rayleigh_sommerfeld": ".propagation",
        "tilt": ".propagation", "propagate_to_plane": ".propagation",
        "resample": ".propagation", "to_device": ".opencl", "Field": ".scene",
        "thin_lens": ".optics", "psnr": ".optics", "ssim": ".optics",
        "adjoint": ".propagation.adjoint", "gerchberg_saxton": ".phase",
        "optimise_phase": ".phase", "double_phase": ".phase",
        "parts_along": ".plate", "record_set": ".plate", "read_plate_set": ".io.plate_set",
        "write_plate_set": ".io.plate_set", "PlateViewer": ".plate.viewer"}
# the packages, imported on first use too (plot needs matplotlib: pip install 'holo[plot]')
_PACKAGES = ("acquired", "camera", "io", "opencl", "optics", "phase", "plate", "plot",
             "propagation", "scene", "units", "validate")
# the names `from holo_core import *` gives (every _API name; test_notebook holds them equal)
__all__ = ["Camera", "Field", "Hologram", "InputError", "Mesh", "Plate", "PlateViewer", "Pupil",
           "RenderResult", "ViewingZone", "adjoint", "angular_spectrum", "autofocus", "double_phase",
           "find_carrier", "fraunhofer", "fresnel", "gerchberg_saxton", "import_acquired",
           "look_at", "object_hologram", "optimise_phase", "parts_along", "physical_field",
           "propagate_to_plane", "psnr", "rayleigh_sommerfeld", "read_acquired",
           "read_hologram", "read_mesh", "read_plate_set", "reconstruct", "record_hologram",
           "record_points", "record_set", "render_camera", "render_view", "resample",
           "sideband", "ssim", "thin_lens", "tilt", "to_device", "unwrap", "write_acquired",
           "write_hologram", "write_plate_set", "write_view"]


__getattr__, __dir__ = lazy_names(__name__, _API, _PACKAGES)
