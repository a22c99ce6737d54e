"""Kernel signatures: a launch by keyword computes what the kernel computes, a wrong argument
fails naming the kernel and the argument, and every signature in holo_core says what its
``.cl`` file declares."""

import importlib
import re
from pathlib import Path

import numpy as np
import pytest

from holo_core.opencl.kernel import BUFFER, REAL, Kernel, kernel
from holo_core.validate import InputError

ROOT = Path(__file__).resolve().parents[3]
SOURCE = """
#ifdef HOLO_FP64
typedef double real;
#else
typedef float real;
#endif
__kernel void axpy(__global float *y, __global const float *x, float a, int n, real b)
{
    int i = get_global_id(0);
    if (i < n) y[i] += a * x[i] + (float)b;
}
"""


@pytest.fixture
def axpy(tmp_path):
    program = tmp_path / "axpy.cl"
    program.write_text(SOURCE)
    return kernel(program, "axpy", y=BUFFER, x=BUFFER, a=np.float32, n=np.int32, b=REAL)


def test_a_launch_by_name_computes_the_kernel(rt, rng, axpy):
    """y + a·x + b against NumPy, the arguments given out of order, an odd length."""
    x, y = (rng.standard_normal(37).astype(np.float32) for _ in range(2))
    yd = rt.to_device(y)
    axpy.launch(
        rt, (40,), options=rt.real_options, n=37, b=0.25, a=1.5, x=rt.to_device(x), y=yd.data
    )
    got = yd.get()
    want = y + np.float32(1.5) * x + np.float32(0.25)
    assert np.allclose(got, want, rtol=1e-6, atol=1e-6), np.max(np.abs(got - want))


@pytest.mark.parametrize(
    "change, says",
    [
        (dict(n=np.zeros(3)), "'n' must be an integer"),
        (dict(n=2.0), "'n' must be an integer"),
        (dict(n=2**31), "'n' = 2147483648 lies outside int32"),
        (dict(a="1.5"), "'a' must be a real number"),
        (dict(a=None), "'a' must be a real number"),
        (dict(x=np.zeros(4, np.float32)), "'x' must be a device array or buffer"),
        (dict(x=3), "'x' must be a device array or buffer"),
        (dict(size=3), "no argument 'size'"),
        (dict(b=None), "'b' must be a real number"),
    ],
)
def test_a_wrong_argument_names_the_kernel_and_the_argument(rt, axpy, change, says):
    buf = rt.to_device(np.zeros(4, np.float32))
    given = dict(y=buf, x=buf, a=1.5, n=4, b=0.0) | change
    with pytest.raises(InputError, match=f"kernel axpy.*{re.escape(says)}"):
        axpy.launch(rt, (4,), options=rt.real_options, **given)


def test_a_missing_argument_is_named(rt, axpy):
    buf = rt.to_device(np.zeros(4, np.float32))
    with pytest.raises(InputError, match=r"kernel axpy: argument 'n' is missing \(4 given of 5"):
        axpy.launch(rt, (4,), options=rt.real_options, y=buf, x=buf, a=1.5, b=0.0)


def test_a_signature_of_the_wrong_count_fails_at_its_first_launch(rt, axpy):
    short = Kernel(axpy.program, "axpy", axpy.args[:-1])
    buf = rt.to_device(np.zeros(4, np.float32))
    with pytest.raises(
        InputError,
        match=r"kernel axpy takes 5 arguments in axpy\.cl; its "
        "signature names 4",
    ):
        short.launch(rt, (4,), options=rt.real_options, y=buf, x=buf, a=1.5, n=4)


def test_real_arguments_need_the_runtime_s_real(rt, axpy):
    if not rt.real_options:
        pytest.skip("this device has no float64: its real is the kernels' default")
    buf = rt.to_device(np.zeros(4, np.float32))
    with pytest.raises(InputError, match="kernel axpy takes real arguments"):
        axpy.launch(rt, (4,), y=buf, x=buf, a=1.5, n=4, b=0.0)


@pytest.mark.parametrize("kind", ["int", int, float, np.ndarray])
def test_an_argument_type_must_be_one_a_kernel_takes(kind):
    """A scalar's width is said (np.int32, not int): the kernel's C type fixes it."""
    with pytest.raises(InputError, match="argument 'n' has type"):
        kernel(Path("k.cl"), "k", n=kind)


# --- every signature in the package against its .cl file ----------------------------------

C_TYPES = {
    "int": np.int32,
    "uint": np.uint32,
    "long": np.int64,
    "float": np.float32,
    "double": np.float64,
    "real": REAL,
}


def declared(source: str) -> dict[str, list[tuple[str, object]]]:
    """kernel name -> [(argument name, BUFFER or its scalar type)] as ``source`` declares."""
    text = re.sub(r"/\*.*?\*/|//[^\n]*", " ", source, flags=re.S)
    found = {}
    for m in re.finditer(r"__kernel\b[^(;{]*?\b(\w+)\s*\(([^)]*)\)", text, re.S):
        args = []
        for p in m.group(2).split(","):
            words = re.findall(r"\w+", p)
            args.append((words[-1], BUFFER if "*" in p else C_TYPES[words[-2]]))
        found[m.group(1)] = args
    return found


def _launching_modules():
    for cl in sorted((ROOT / "holo_core").rglob("*.cl")):
        name = ".".join(cl.relative_to(ROOT).with_suffix("").parts)
        yield cl, importlib.import_module(name)


@pytest.mark.parametrize(
    "cl, module", list(_launching_modules()), ids=lambda v: v.name if isinstance(v, Path) else ""
)
def test_each_kernel_is_launched_by_a_signature_that_says_what_the_cl_file_declares(cl, module):
    """Every kernel of a ``.cl`` file has one signature in its module, naming its arguments
    in the file's order with their types."""
    signatures = {
        k.name: k for k in vars(module).values() if isinstance(k, Kernel) and Path(k.program) == cl
    }
    kernels = declared(cl.read_text())
    assert sorted(signatures) == sorted(kernels), f"{cl.name}: kernels without a signature"
    for name, args in kernels.items():
        said = [
            (a.name, a.type if a.type in (BUFFER, REAL) else np.dtype(a.type).type)
            for a in signatures[name].args
        ]
        assert said == args, f"{cl.name} {name}: signature {said} against the file's {args}"


def test_the_cl_reader_reads_a_declaration():
    """A declaration across lines with comments and qualifiers, read as the file says."""
    got = declared(
        "__kernel void k(__global float2 *out, /* a, b */ int n, // the rows\n"
        " __constant real *h, real z, long first) {}"
    )
    assert got == {
        "k": [("out", BUFFER), ("n", np.int32), ("h", BUFFER), ("z", REAL), ("first", np.int64)]
    }
