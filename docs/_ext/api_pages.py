"""The API reference, written at build time from the code: every name in ``holo_core.__all__``
under the package that defines it, and each package of ``holo_core`` with its own docstring.

Nothing is listed by hand, so a module that moves inside a package moves on the page too.
"""

import importlib
import inspect
import sys
from pathlib import Path

from docstrings import escaped
from sphinx.pycode import ModuleAnalyzer, PycodeError

import holo_core

OUT = "reference/generated"


def _kind(obj):
    if inspect.isclass(obj):
        return "exception" if issubclass(obj, BaseException) else "class"
    if callable(obj):
        return "function"
    return "data"


def _options(obj, path=""):
    """A table's value is its docstring's business, not a repr of its functions; its
    docstring (the string after its assignment) is read where it is assigned, which for a
    package's name is one of the package's modules, not the package autodoc reads."""
    if _kind(obj) != "data":
        return []
    return [
        "   :no-value:",
        "",
        *("   " + escaped(line) if line else "" for line in _attribute_doc(path)),
    ]


def _attribute_doc(path):
    """The lines of the docstring after ``path``'s assignment, in the module or one of the
    package's modules that assigns it (empty where none has one)."""
    package, _, name = path.rpartition(".")
    for module in sorted(m for m in sys.modules if m == package or m.startswith(package + ".")):
        try:
            docs = ModuleAnalyzer.for_module(module).find_attr_docs()
        except PycodeError:  # a module without source (a C extension)
            continue
        if ("", name) in docs:
            return list(docs[("", name)])
    return []


def _packages():
    """The subpackages ``dir(holo_core)`` names beside the API (the core's own floors)."""
    names = []
    for name in dir(holo_core):
        if name.startswith("_") or name in holo_core.__all__:
            continue
        try:
            module = importlib.import_module(f"holo_core.{name}")
        except ImportError:  # an optional package whose dependency is absent (plot)
            continue
        if inspect.ismodule(module) and module.__name__ == f"holo_core.{name}":
            names.append(name)
    return names


def _heading(text, mark):
    return [text, mark * len(text), ""]


def write(app):
    out = Path(app.srcdir) / OUT
    out.mkdir(parents=True, exist_ok=True)
    groups = {}
    for name in holo_core.__all__:
        obj = getattr(holo_core, name)
        home = getattr(obj, "__module__", "holo_core") or "holo_core"
        package = ".".join(home.split(".")[:2])
        groups.setdefault(package, []).append((name, obj, home))
    lines = [
        *_heading("The top-level names", "="),
        "Every name in ``holo_core.__all__``, under the package that defines it. "
        "``import holo_core as hc`` gives them all (``hc.angular_spectrum``, "
        "``hc.Camera``, …).",
        "",
        ".. currentmodule:: holo_core",
        "",
    ]
    for package in sorted(groups):
        lines += _heading(f"From ``{package}``", "-")
        for name, obj, home in groups[package]:
            lines += [
                f".. auto{_kind(obj)}:: holo_core.{name}",
                *_options(obj, f"holo_core.{name}"),
                "",
                f"   *Defined in* ``{home}``.",
                "",
            ]
    _write(out / "names.rst", lines)
    lines = [
        *_heading("The packages", "="),
        "The floors of ``holo_core``, each with the files it holds (the package's docstring).",
        "",
    ]
    top = {id(getattr(holo_core, n)): n for n in holo_core.__all__}
    for name in _packages():
        module = importlib.import_module(f"holo_core.{name}")
        lines += [*_heading(f"``holo_core.{name}``", "-"), f".. automodule:: holo_core.{name}", ""]
        again = []
        for member in getattr(module, "__all__", ()):
            obj = getattr(module, member)
            if id(obj) in top:  # documented once, under its top-level name
                again.append(f":py:obj:`holo_core.{top[id(obj)]}`")
            elif not inspect.ismodule(obj):
                lines += [
                    f".. auto{_kind(obj)}:: holo_core.{name}.{member}",
                    *_options(obj, f"holo_core.{name}.{member}"),
                    "",
                ]
        if again:
            lines += ["Also here: " + ", ".join(again) + ".", ""]
    _write(out / "packages.rst", lines)


def _write(path, lines):
    text = "\n".join(lines)
    if not path.exists() or path.read_text() != text:  # unchanged pages are not rebuilt
        path.write_text(text)


def setup(app):
    app.connect("builder-inited", write)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
