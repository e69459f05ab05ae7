"""What the compiled backends run for a shape: its tape (or specialised program) and numbers.

:func:`compiled_program` chooses by :func:`kernel_mode` between the tape interpreter of the
shape's dimension (:mod:`ndpack.kernels.tape`) and code generated for the tree
(:mod:`ndpack.kernels.program`), and keeps the result on the shape. The shapes take part only
through their protocol (``dim``, ``_tape``, ``_kernel`` and ``_kernel_advice``), so this layer
imports none of them.
"""

from __future__ import annotations

import os

from ..errors import BackendError, KernelError
from .program import build
from .tape import Flat, TapeTooDeep, flatten

#: How the compiled backends get a shape's distance: "tape" (the default: numbers for the
#: interpreter of its dimension, nothing to compile for a new shape) or "specialised" (code
#: generated for the tree, compiled for each new tree; see ndpack.kernels.program).
KERNEL_MODES = ("tape", "specialised")


def kernel_mode() -> str:
    """``$NDPACK_KERNELS``, or "tape"; checked."""
    mode = os.environ.get("NDPACK_KERNELS") or "tape"
    if mode not in KERNEL_MODES:
        raise BackendError(f"NDPACK_KERNELS must be one of {', '.join(KERNEL_MODES)}, got {mode!r}")
    return mode


def compiled_program(shape) -> Flat:
    """What the compiled backends run for ``shape`` (:class:`~ndpack.kernels.tape.Flat`: the
    program and the shape's numbers), made once per shape and :func:`kernel_mode`.

    A tree too deep for the tape falls back to a specialised program.

    Raises
    ------
    BackendError
        If the shape has no scalar kernel (a NumPy-only plug-in), saying what to do: the advice
        is the shape's own (``shape._kernel_advice()``, see :class:`ndpack.oracle.Oracle`).
    """
    mode = kernel_mode()
    made = shape.__dict__.setdefault("_ndpack_flat", {})
    if mode not in made:
        try:
            flat = None
            if mode == "tape":
                try:
                    flat = flatten(shape)
                except TapeTooDeep:  # compiled for itself instead
                    pass
            if flat is None:
                program = build(shape)
                flat = Flat(program, program.param_array(), program.device_values)
        except KernelError as error:
            advice = getattr(shape, "_kernel_advice", None)
            advice = advice() if advice is not None else "Use backend='numpy'"
            raise BackendError(f"{shape!r} cannot run on a compiled backend: {error}. {advice}") from None
        made[mode] = flat
    return made[mode]


def has_kernel(shape) -> bool:
    """Whether ``shape`` compiles to a scalar kernel (so the compiled backends can run it)."""
    try:
        compiled_program(shape)
    except BackendError:
        return False
    return True
