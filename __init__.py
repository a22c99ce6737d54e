"""The extension's entry point: the repository root is the extension root (blender_manifest.toml);
Blender imports it as ``bl_ext.<repository>.holo``. The add-on lives in ``holo_addon``, the core
ships as the ``holo`` wheel. Nothing of Blender is imported until Blender registers the add-on:
pytest imports this file as the root package of every test, core and physics too."""


def register():
    from .holo_addon import register

    register()


def unregister():
    from .holo_addon import unregister

    unregister()
