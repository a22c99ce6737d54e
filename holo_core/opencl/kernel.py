"""A kernel's signature, written once beside the module that launches it, and its launch by
keyword: each argument named as in the ``.cl`` file and typed (a device buffer, a NumPy scalar
type, or the kernels' ``real``), so that a launch reads without the ``.cl`` file open and a
wrong argument fails naming the kernel and the argument::

    MULTIPLY_TILED = kernel(PROGRAM, "multiply_tiled", acc=BUFFER, m=BUFFER, k=BUFFER,
                            h=np.int32, w=np.int32, first=np.int32)
    MULTIPLY_TILED.launch(rt, global_size, acc=acc, m=spectrum, k=psf, h=h, w=w, first=0)

The scalars are cast to their types here, and pyopencl is told the types once per kernel
object (``set_scalar_arg_dtypes``), so that it packs them without asking each call.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

from ..validate import InputError

BUFFER = "buffer"  # a ``__global`` or ``__constant`` pointer: a device array or buffer
REAL = "real"  # the kernels' ``real``: the runtime's (float64 where the device has it)


@dataclass(frozen=True, slots=True)
class Arg:
    """One argument of a kernel: its name in the ``.cl`` file and its type (BUFFER, REAL or a
    NumPy scalar type such as ``np.int32``)."""

    name: str
    type: object

    def __post_init__(self):
        if self.type not in (BUFFER, REAL) and not (
            isinstance(self.type, type) and issubclass(self.type, np.number)
        ):
            raise InputError(
                f"argument {self.name!r} has type {self.type!r}; allowed: "
                "BUFFER, REAL or a NumPy scalar type (np.int32, np.float32, …)"
            )


@dataclass(frozen=True, slots=True)
class Kernel:
    """The kernel ``name`` of the program ``program`` (a ``.cl`` file) and its arguments in
    the order the ``.cl`` file declares them."""

    program: Path
    name: str
    args: tuple[Arg, ...]

    def launch(self, rt, global_size, local_size=None, /, *, options=(), **values):
        """Enqueue the kernel on ``rt``'s queue over ``global_size`` (work groups of
        ``local_size``, None: the driver's), built with ``options``, each argument given by
        name. Raises :class:`~holo_core.validate.InputError` naming the kernel and the
        argument for one missing, unknown or of the wrong kind."""
        return self._kernel(rt, tuple(options))(
            rt.queue, global_size, local_size, *self._values(rt, values)
        )

    def _values(self, rt, given: dict) -> list:
        """The arguments ``given`` by name, in the kernel's order: buffers as they are (a
        device array's buffer), scalars cast to their types."""
        names = [a.name for a in self.args]
        unknown = [n for n in given if n not in names]
        if unknown:
            raise InputError(
                f"kernel {self.name} has no argument {unknown[0]!r}; its "
                f"arguments: {', '.join(names)}"
            )
        missing = [n for n in names if n not in given]
        if missing:
            raise InputError(
                f"kernel {self.name}: argument {missing[0]!r} is missing "
                f"({len(given)} given of {len(names)})"
            )
        return [self._value(a, given[a.name], rt) for a in self.args]

    def _value(self, arg: Arg, value, rt):
        if arg.type == BUFFER:
            if isinstance(value, cla.Array):
                return value.data
            if isinstance(value, cl.MemoryObjectHolder):
                return value
            raise InputError(
                f"kernel {self.name}: argument {arg.name!r} must be a device "
                f"array or buffer; got {type(value).__name__}"
            )
        dtype = np.dtype(rt.real if arg.type == REAL else arg.type)
        if dtype.kind in "iu":
            if not isinstance(value, (numbers.Integral, np.bool_)):
                raise InputError(
                    f"kernel {self.name}: argument {arg.name!r} must be an "
                    f"integer ({dtype}); got {type(value).__name__} {value!r}"
                )
            limits = np.iinfo(dtype)
            if not limits.min <= value <= limits.max:
                raise InputError(
                    f"kernel {self.name}: argument {arg.name!r} = {value} lies "
                    f"outside {dtype}'s [{limits.min}, {limits.max}]"
                )
        elif not isinstance(value, numbers.Real):
            raise InputError(
                f"kernel {self.name}: argument {arg.name!r} must be a real "
                f"number ({dtype}); got {type(value).__name__}"
            )
        return dtype.type(value)

    def _kernel(self, rt, options: tuple[str, ...]) -> cl.Kernel:
        """The kernel object, told its scalar types once; its argument count checked against
        the program's, and the program built with the runtime's ``real`` where the kernel
        takes one."""
        key = ("typed kernel", self.program, self.name, options)
        if key not in rt.cache:
            if any(a.type == REAL for a in self.args) and not set(rt.real_options) <= set(options):
                raise InputError(
                    f"kernel {self.name} takes real arguments: its options must "
                    f"hold the runtime's {rt.real_options}; got {options}"
                )
            k = rt.kernel(self.program, self.name, options)
            if k.num_args != len(self.args):
                raise InputError(
                    f"kernel {self.name} takes {k.num_args} arguments in "
                    f"{Path(self.program).name}; its signature names "
                    f"{len(self.args)}"
                )
            k.set_scalar_arg_dtypes(
                [
                    None if a.type == BUFFER else np.dtype(rt.real if a.type == REAL else a.type)
                    for a in self.args
                ]
            )
            rt.cache[key] = k
        return rt.cache[key]


def kernel(program: Path, name: str, /, **types) -> Kernel:
    """The signature of the kernel ``name`` of ``program``, its arguments given in the
    ``.cl`` file's order as ``name=type`` (BUFFER, REAL or a NumPy scalar type)."""
    return Kernel(program, name, tuple(Arg(n, t) for n, t in types.items()))
