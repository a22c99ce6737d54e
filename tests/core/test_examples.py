"""The Examples section of every public name's docstring runs and prints what it says.

Collected from ``holo_core.__all__`` and from each package's own ``__all__`` (the names the
API reference renders), so that the suite runs them where it runs (``tests/core``, NumPy 1
and 2) and holds every top-level name to having an example; ``pytest --doctest-modules`` on a
module runs the same examples.
"""

import contextlib
import doctest
import importlib
import inspect
import sys

import numpy as np
import pytest

import holo_core

_FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _examples():
    for name in holo_core.__all__:
        doc = inspect.getdoc(getattr(holo_core, name)) or ""
        if ">>>" in doc:
            yield name, doc


def _package_examples():
    """(holo_core.package.name, docstring) of each package's own public names with Examples
    (a name also in ``holo_core.__all__`` is run there)."""
    top = {id(getattr(holo_core, n)) for n in holo_core.__all__}
    for package in sorted(dir(holo_core)):
        if package.startswith("_") or package in holo_core.__all__:
            continue
        try:
            module = importlib.import_module(f"holo_core.{package}")
        except ImportError:  # an optional extra's package (plot without matplotlib)
            continue
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            doc = inspect.getdoc(obj) or ""
            if id(obj) not in top and not inspect.ismodule(obj) and ">>>" in doc:
                yield f"{package}.{name}", doc


def _run(name, doc):
    test = doctest.DocTestParser().get_doctest(doc, {}, f"holo_core.{name}", None, 0)
    runner = doctest.DocTestRunner(optionflags=_FLAGS)
    report = []
    # NumPy 2 writes a scalar as np.float64(…); the examples print NumPy 1's form, which 2 keeps
    # under its legacy print mode (make test-numpy2 runs them there)
    legacy = (
        np.printoptions(legacy="1.25")
        if np.lib.NumpyVersion(np.__version__) >= "2.0.0"
        else contextlib.nullcontext()
    )
    try:
        with legacy:
            runner.run(test, out=report.append)
    finally:
        if "matplotlib.pyplot" in sys.modules:  # the plots' examples leave their figures open
            sys.modules["matplotlib.pyplot"].close("all")
    assert runner.failures == 0, "".join(report)


def test_every_public_name_has_an_example():
    missing = sorted(set(holo_core.__all__) - {name for name, _ in _examples()})
    assert not missing, f"public names without Examples: {missing}"


@pytest.mark.parametrize(("name", "doc"), [pytest.param(n, d, id=n) for n, d in _examples()])
def test_example(name, doc):
    _run(name, doc)


@pytest.mark.parametrize(
    ("name", "doc"), [pytest.param(n, d, id=n) for n, d in _package_examples()]
)
def test_package_example(name, doc):
    _run(name, doc)
