"""The Examples section of every public name's docstring runs and prints what it says.

Collected from ``holo_core.__all__`` rather than by ``--doctest-modules``: several public
functions are wrapped (batching, progress, input checks), and doctest's module walk skips a
wrapper whose globals are another module's.
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
