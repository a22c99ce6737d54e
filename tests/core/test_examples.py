"""The Examples section of every public name's docstring runs and prints what it says.

Collected from ``holo_core.__all__``, the names the API reference renders, so that the suite
runs them where it runs (``tests/core``, NumPy 1 and 2) and holds every public name to having
an example; ``pytest --doctest-modules`` on a module runs the same examples.
"""

import contextlib
import doctest
import inspect

import numpy as np
import pytest

import holo_core

_FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _examples():
    for name in holo_core.__all__:
        doc = inspect.getdoc(getattr(holo_core, name)) or ""
        if ">>>" in doc:
            yield name, doc


def test_every_public_name_has_an_example():
    missing = sorted(set(holo_core.__all__) - {name for name, _ in _examples()})
    assert not missing, f"public names without Examples: {missing}"


@pytest.mark.parametrize(("name", "doc"), [pytest.param(n, d, id=n) for n, d in _examples()])
def test_example(name, doc):
    test = doctest.DocTestParser().get_doctest(doc, {}, f"holo_core.{name}", None, 0)
    runner = doctest.DocTestRunner(optionflags=_FLAGS)
    report = []
    # NumPy 2 writes a scalar as np.float64(…); the examples print NumPy 1's form, which 2 keeps
    # under its legacy print mode (make test-numpy2 runs them there)
    legacy = (np.printoptions(legacy="1.25") if np.lib.NumpyVersion(np.__version__) >= "2.0.0"
              else contextlib.nullcontext())
    with legacy:
        runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)
