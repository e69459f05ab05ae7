"""Scalar kernels: every shape's signed distance, written once and compiled for each backend.

:mod:`~ndpack.kernels.language` defines the subset of Python the kernels are written in and
prints it for Numba (CPU and CUDA) and Warp; :mod:`~ndpack.kernels.library` holds the built-in
shapes' kernels; :mod:`~ndpack.kernels.program` assembles a shape tree into one program.
"""

from .language import MATH_FUNCTIONS, Kernel
from .program import ENTRY, Program, build

__all__ = ["ENTRY", "MATH_FUNCTIONS", "Kernel", "Program", "build"]
