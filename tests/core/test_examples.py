"""The Examples section of every public name's docstring runs and prints what it says.

Collected from ``holo_core.__all__`` rather than by ``--doctest-modules``: several public
functions are wrapped (batching, progress, input checks), and doctest's module walk skips a
wrapper whose globals are another module's.
"""

import doctest
import inspect

import pytest

import holo_core

_FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _examples():
    for name in holo_core.__all__:
        doc = inspect.getdoc(getattr(holo_core, name)) or ""
        if ">>>" in doc:
            yield name, doc


@pytest.mark.parametrize(("name", "doc"), [pytest.param(n, d, id=n) for n, d in _examples()])
def test_example(name, doc):
    test = doctest.DocTestParser().get_doctest(doc, {}, f"holo_core.{name}", None, 0)
    runner = doctest.DocTestRunner(optionflags=_FLAGS)
    report = []
    runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)
