"""The kernels written once for every compiled backend, as text to print.

:mod:`ndpack.backends.move_kernels` (the move), :mod:`ndpack.backends.index_kernels` (the sphere
index's queries) and :mod:`ndpack.backends.store_kernels` (the GPU backends' store and array
kernels) are read, not imported, and printed for each backend by
:func:`ndpack.kernels.portable.render`: Numba's print takes the first two, the GPU backends' the
third too.
"""

from __future__ import annotations

from pathlib import Path

#: The files of the kernels written once, in the order a backend's module holds them.
MOVE, INDEX, STORE = "move_kernels.py", "index_kernels.py", "store_kernels.py"


def portable_text(*names: str) -> str:
    """The kernels of the files ``names`` (of this folder) as one text: :func:`~ndpack.kernels.portable.render`
    prints a function that writes points together with its callers."""
    return "\n\n".join(Path(__file__).with_name(name).read_text() for name in names)
