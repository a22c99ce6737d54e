"""The extension's entry point: the repository root is the extension root (blender_manifest.toml);
Blender imports it as ``bl_ext.<repository>.holo``. The add-on lives in ``holo_addon``, the core
ships as the ``holo`` wheel."""

from .holo_addon import register, unregister  # noqa: F401
