"""A package's names imported on first use (PEP 562): importing the package stays light, so
the planner and Blender's process use parts of it without loading the OpenCL driver."""

from __future__ import annotations

import sys
import types
from importlib import import_module


def lazy_names(package: str, api: dict, packages=()):
    """(``__getattr__``, ``__dir__``) for the package ``package``: each name of ``api`` comes
    from the submodule it maps to (relative, ``.lens``), each of ``packages`` is a subpackage,
    all imported when first asked for."""

    def __getattr__(name):
        if name in packages:
            return import_module(f".{name}", package)
        if name not in api:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(import_module(api[name], package), name)

    def __dir__():
        return sorted({*vars(sys.modules[package]), *api, *packages})

    return __getattr__, __dir__


def lazy_package(package: str, api: dict) -> None:
    """Make the imported package ``package`` serve each name of ``api`` from the submodule it
    maps to, on first use, even where a submodule of the same name has been imported since
    (PEP 562's ``__getattr__`` then no longer asks: the import sets the module as the
    package's attribute)."""

    class LazyPackage(types.ModuleType):
        def __getattribute__(self, name):
            if name in api:
                return getattr(import_module(api[name], package), name)
            return super().__getattribute__(name)

        def __dir__(self):
            return sorted({*super().__dir__(), *api})

    sys.modules[package].__class__ = LazyPackage
