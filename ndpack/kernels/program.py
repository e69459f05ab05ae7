"""A kernel program: scalar functions in the kernel language, printed for each compiler.

What the compiled backends run is a program. Usually it is the tape interpreter of a dimension
(:mod:`ndpack.kernels.tape`), which takes any tree of built-in shapes as numbers. A shape can
also be *specialised* (:func:`build`): each oracle adds itself with ``_kernel(program) ->
name``, appending its numbers to the flat parameter array, using library functions
(:mod:`ndpack.kernels.library`) or defining small wrappers, and returning the name of a function
``name(p, prm)`` giving its signed distance. That text holds the tree's structure and the
offsets of its numbers, so each new tree (and each mesh placed after other shapes) compiles
again: it is an opt-in (``NDPACK_KERNELS=specialised``) and the fallback for trees too deep for
the tape.
"""

from __future__ import annotations

import ast
import hashlib
import inspect
import textwrap

import numpy as np

from ..errors import KernelError
from .language import Kernel, warp_prelude

#: Name of the entry function every compiled module exposes.
ENTRY = "sd"
#: The gradient entries every compiled module exposes too (see :meth:`Program.add_gradient`):
#: ``sd_feature(p, prm, hint, bound)``, ``sd_at(p, prm, f)`` and ``sd_slope(p, prm, f, value, k)``.
FEATURE, AT_FEATURE, SLOPE = "sd_feature", "sd_at", "sd_slope"
#: What they are for a shape with no closed-form gradient: no feature (-1), so the backends take
#: central differences of ``sd``; the compilers fold the constant away.
NO_GRADIENT = f"""def {FEATURE}(p, prm, hint: float, bound: float):
    return -1.0


def {AT_FEATURE}(p, prm, f: float):
    return {ENTRY}(p, prm)


def {SLOPE}(p, prm, f: float, value: float, k: int):
    return 0.0
"""


class Program:
    """Kernel functions of one shape, in call order, and its parameters.

    Parameters
    ----------
    dim : int
        Dimension of the points.
    """

    def __init__(self, dim: int, title: str | None = None):
        self.dim = int(dim)
        #: What the program is for, in a few words (generated modules start with it).
        self.title = title or f"a {self.dim}-D shape"
        #: Names of kernels that Numba's CPU compiler should inline into their (single) caller.
        self.inline: set[str] = set()
        self.kernels: dict[str, Kernel] = {}
        self._chunks: list[np.ndarray] = []  # the parameters, as (k,) float64 pieces in order
        self._size = 0
        self._shapes: dict[int, str] = {}
        self._defined = 0
        #: Warp float32 replacements of kernels, by name: native Warp code (wp.Mesh queries)
        #: where the kernel language has no equivalent; the checked kernel stays the fallback.
        self.warp_natives: dict[str, str] = {}
        #: (offset, count, resolve): parameters known only on a device; ``resolve(device)`` gives
        #: the ``count`` values a Warp backend writes there (the host copy holds zeros).
        self.device_values: list[tuple] = []
        self._gradients: dict[int, tuple[str, str, str]] = {}

    # ------------------------------------------------------------------ building
    def add_params(self, values) -> int:
        """Append float values to the parameter array; returns the offset of the first."""
        # Kept as arrays: a mesh adds millions of numbers, which a list of floats would hold slowly.
        chunk = np.array(values, dtype=np.float64).ravel()
        offset = self._size
        self._chunks.append(chunk)
        self._size += chunk.size
        return offset

    @property
    def next_offset(self) -> int:
        """The offset the next :meth:`add_params` returns (for blocks that hold absolute offsets)."""
        return self._size

    @property
    def params(self) -> np.ndarray:
        """(k,) float64: every parameter added so far."""
        return np.concatenate(self._chunks) if self._chunks else np.zeros(0)

    def use(self, fn, name: str | None = None) -> str:
        """Add a library function (and the functions of its module it calls); returns its name.

        Library functions live in :mod:`ndpack.kernels.library` or in another module of kernel
        functions (the mesh queries, for example); a call resolves within the caller's module.
        ``name`` adds the function under another name, which code added later calls (how one
        tree walk calls the triangle or the segment query, whichever the dimension needs).
        """
        name = name or fn.__name__
        if name not in self.kernels:
            source = textwrap.dedent(inspect.getsource(fn))
            # The names it calls (from the syntax tree, so a longer name such as rounded_box
            # does not count as a call of box, nor does a name in a comment).
            tree = ast.parse(source)
            called = {node.func.id for node in ast.walk(tree)
                      if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)}
            for other in list(fn.__globals__.values()):
                if inspect.isfunction(other) and other is not fn and other.__name__ in called:
                    self.use(other)
            if name != fn.__name__:
                source = source.replace(f"def {fn.__name__}(", f"def {name}(", 1)
            self.kernels[name] = Kernel(source if name != fn.__name__ else fn, callees=self.kernels)
        return name

    def add_gradient(self, oracle, feature: str, at: str, slope: str) -> None:
        """Record that ``oracle``'s distance has a closed-form gradient, in three functions:
        ``feature(p, prm, hint, bound)`` a number naming the boundary feature nearest to ``p``
        (>= 0; the expensive search, which ``hint``, a feature found near ``p`` before or -1,
        may speed up; -2 where no feature is nearer than ``bound``, which only a closed surface
        may report, see :func:`ndpack.meshes.kernels.surface_feature`), ``at(p, prm, f)`` the
        signed distance given it (equal to the distance function's), and
        ``slope(p, prm, f, value, k)`` component ``k`` of the unit gradient given it and that
        distance. A top-level shape's become the module's gradient entries:
        the backends then move a prototype by one search a step instead of ``2 D + 1`` distances.
        """
        self._gradients[id(oracle)] = (feature, at, slope)

    def add_device_values(self, offset: int, count: int, resolve) -> None:
        """Mark ``count`` parameters from ``offset`` as filled per device by ``resolve(device)``."""
        self.device_values.append((offset, count, resolve))

    def define(self, source: str) -> str:
        """Add a generated function written as ``def _(p, prm): ...``; returns its unique name."""
        name = f"k{self._defined}"
        self._defined += 1
        if not source.lstrip().startswith("def _("):
            raise ValueError("generated kernels are written as 'def _(p, prm): ...'")
        self.kernels[name] = Kernel(source.replace("def _(", f"def {name}(", 1), callees=self.kernels)
        return name

    def add_functions(self, source: str) -> None:
        """Add the functions of ``source`` (kernel-language text, functions apart by two blank
        lines) under their own names."""
        for text in source.split("\n\n\n"):
            kernel = Kernel(text.strip() + "\n", callees=self.kernels)
            self.kernels[kernel.name] = kernel

    def add_kernel(self, kernel: Kernel) -> str:
        """Add an already checked kernel (a user's plug-in); returns the name to call it by.

        Its code is added once, however many shapes use it (one function made into several
        scalar plug-ins with other parameters: each reads its own through its offset). Another
        function under a name already taken (two functions ``f`` of two modules) is added under
        a numbered name, ``user_f_2``.
        """
        name, number = kernel.name, 1
        while name in self.kernels:
            if self.kernels[name] is kernel or self.kernels[name].same_code(kernel):
                return name
            number += 1
            name = f"{kernel.name}_{number}"
        self.kernels[name] = kernel if name == kernel.name else kernel.renamed(name)
        return name

    def shape(self, oracle) -> str:
        """Name of the distance function of ``oracle`` (a child in a CSG tree), added once."""
        key = id(oracle)
        if key not in self._shapes:
            kernel = getattr(oracle, "_kernel", None)
            if kernel is None:
                raise KernelError(f"{oracle!r} has no scalar kernel")
            self._shapes[key] = kernel(self)
        return self._shapes[key]

    # ------------------------------------------------------------------ output
    def source(self, dialect: str, float_name: str = "float64") -> str:
        """All functions in ``dialect``, then ``sd(p, prm)`` calling the shape's entry."""
        parts = [self.warp_natives[name] if dialect == "warp" and float_name == "float32" and name in self.warp_natives
                 else kernel.render(dialect, self.dim, float_name) for name, kernel in self.kernels.items()]
        text = "\n\n\n".join(parts) + "\n"
        if dialect == "warp":  # the helpers that give // and % Python's meaning
            text = warp_prelude(float_name, text) + text
        return text

    @property
    def key(self) -> str:
        """Hash of the program's structure: equal keys compile to equal code."""
        return hashlib.sha1(f"{self.dim}\n{self.source('numba')}".encode()).hexdigest()[:16]

    def param_array(self, dtype=np.float64) -> np.ndarray:
        """(k,) the flat parameters; never empty (some compilers reject empty arrays)."""
        params = self.params
        return (params if params.size else np.zeros(1)).astype(dtype)


def build(shape) -> Program:
    """The kernel program of ``shape``, whose distance function is ``program.entry``.

    Raises
    ------
    KernelError
        If a part of the shape has no scalar kernel (a NumPy-only plug-in).
    """
    name = " ".join(repr(shape).split())
    program = Program(shape.dim, f"{shape.dim}-D {name[:60]}{'...' if len(name) > 60 else ''} (specialised)")
    entry = program.shape(shape)
    program.kernels[ENTRY] = Kernel(f"def {ENTRY}(p, prm):\n    return {entry}(p, prm)\n", callees=program.kernels)
    _add_gradient_entries(program, program._gradients.get(id(shape)))
    return program


def _add_gradient_entries(program: Program, gradient) -> None:
    """Define ``sd_feature``, ``sd_at`` and ``sd_slope``: calls of the shape's ``gradient``
    functions (feature, at, slope), or the stubs that say there is none."""
    if gradient is None:
        source = NO_GRADIENT
    else:
        feature, at, slope = gradient
        source = (f"def {FEATURE}(p, prm, hint: float, bound: float):\n"
                  f"    return {feature}(p, prm, hint, bound)\n\n\n"
                  f"def {AT_FEATURE}(p, prm, f: float):\n    return {at}(p, prm, f)\n\n\n"
                  f"def {SLOPE}(p, prm, f: float, value: float, k: int):\n    return {slope}(p, prm, f, value, k)\n")
    program.add_functions(source)
