"""A shape as data: a tape of instructions that one precompiled interpreter evaluates.

A tree of built-in shapes (every primitive, every CSG operation and transform, meshes and
outlines as leaves) is flattened into numbers only: instructions in postfix order and the
leaves' parameters, in one flat array ``prm``. The interpreter, :func:`interpreter`, is kernel-
language code that depends on the dimension and on the users' scalar plug-ins in the tree, never
on the tree or its numbers, so a new size, a new mesh or a new CSG tree compiles nothing: the
compiled interpreter of that dimension (kept on disk, see :mod:`ndpack.kernels.compile`) runs it.

Layout of ``prm``
-----------------
- ``prm[0]``: the instruction count; ``prm[1]``: the offset of the surface block when the whole
  shape is one untransformed mesh or outline (its closed-form gradient then serves the
  backends), else -1; ``prm[2]``: the offset of the first instruction.
- The leaves' parameters, transform blocks and constants, from offset :data:`HEADER`.
- The instructions, three numbers each: ``(opcode, argument, transform)``.

Instructions
------------
A leaf (opcode >= 0) pushes its distance: opcode ``k < SURFACE`` is ``LEAVES[k]`` of
:mod:`ndpack.kernels.library`, :data:`SURFACE` a mesh or outline, ``USER + k`` the ``k``-th
user plug-in; the argument is the offset of its parameters. Its transform, the offset of a block
``[A (D x D, row-major), b (D), factor]`` or -1, maps the point to ``q = A p + b`` and scales
the distance by ``factor``: the composition of every translation, rotation and uniform scale on
the way from the root, so a transform costs nothing at inner nodes. Value operations (opcodes
< 0) combine the top of the value stack: ``MIN`` (union), ``MAX`` (intersection),
``DIFFERENCE`` (``max(a, -b)``), ``NEGATE`` (complement), and with a constant at the argument
``OFFSET`` (``v - c``), ``SHELL`` (``|v| - c``) and ``SMOOTH`` (smooth union of blend ``c``);
constants under a scale are stored scaled, since each of these commutes with ``factor * v``.

The value stack lives in :data:`REGISTERS` scalars (no array: no allocation per call on the CPU,
registers on the GPU). Nested unions and intersections are flattened, so the usual trees (chains
of ``|``, ``&`` and ``-``) need two; a tree that needs more than :data:`REGISTERS` raises
:class:`TapeTooDeep` and is compiled as generated code instead (:mod:`ndpack.kernels.program`).
"""

from __future__ import annotations

import contextlib
import hashlib

import numpy as np

from ..errors import KernelError
from . import library
from .language import Kernel
from .program import AT_FEATURE, ENTRY, FEATURE, NO_GRADIENT, SLOPE, Program

#: The primitives' kernels, by opcode (the order is the tape format: append only).
LEAVES = (library.ball, library.box, library.rounded_box, library.half_space, library.slab, library.capsule,
          library.cylinder, library.polytope, library.ellipsoid, library.torus)
#: Primitives that exist in one dimension only.
ONLY_IN = {library.torus: 3}
SURFACE = len(LEAVES)
USER = 16
MIN, MAX, DIFFERENCE, NEGATE, OFFSET, SHELL, SMOOTH = -1, -2, -3, -4, -5, -6, -7
#: Values the stack holds at most: the accumulator and ``REGISTERS - 1`` scalars below it.
REGISTERS = 8
#: Numbers per instruction, and before the parameters.
WIDTH, HEADER = 3, 3


class TapeTooDeep(KernelError):
    """The tree needs more than :data:`REGISTERS` values at once (a deeply nested tree)."""


class Flat:
    """A shape flattened for the compiled backends: the program that evaluates it and its numbers.

    Attributes
    ----------
    program : Program
        The compiled code: the interpreter of a tape (shared by every shape of its dimension and
        plug-ins) or a shape's own generated program.
    params : (k,) float64
        The shape's numbers (for a tape: header, parameters and instructions).
    device_values : list of (offset, count, resolve)
        Parameters known only on a device (a Warp mesh's id, see :meth:`Program.add_device_values`).
    """

    def __init__(self, program: Program, params: np.ndarray, device_values=()):
        self.program = program
        self.params = params if params.size else np.zeros(1)
        self.device_values = list(device_values)


class Tape:
    """Builder of a shape's tape; shapes add themselves with ``_tape(tape)``.

    Parameters
    ----------
    dim : int
    """

    def __init__(self, dim: int):
        self.dim = int(dim)
        self.instructions: list[list[float]] = []
        self._chunks: list[np.ndarray] = [np.zeros(HEADER)]
        self._size = HEADER
        self.users: list[Kernel] = []
        self.device_values: list[tuple] = []
        # The current transform, composed from the root: [A, b, factor, block offset or None].
        self._transforms = [[np.eye(self.dim), np.zeros(self.dim), 1.0, None]]
        self._height = 0
        self.depth = 0
        self._surfaces = None  # the surface queries (see surface), where the tree holds a surface

    # ------------------------------------------------------------------ what shapes call
    def add(self, shape) -> None:
        """Append the instructions of ``shape`` (a child in a tree)."""
        method = getattr(shape, "_tape", None)
        if method is None:
            raise KernelError(f"{shape!r} has no scalar kernel")
        method(self)

    def params(self, values) -> int:
        """Append numbers; returns the offset of the first."""
        chunk = np.array(values, dtype=np.float64).ravel()
        offset = self._size
        self._chunks.append(chunk)
        self._size += chunk.size
        return offset

    @property
    def next_offset(self) -> int:
        """The offset the next :meth:`params` returns (for blocks that hold absolute offsets)."""
        return self._size

    def leaf(self, function, values) -> None:
        """A primitive whose distance is the library ``function`` (one of :data:`LEAVES`) on ``values``."""
        self._push(LEAVES.index(function), self.params(values))

    def add_device_values(self, offset: int, count: int, resolve) -> None:
        """Mark ``count`` numbers from ``offset`` as filled per device by ``resolve(device)`` (the
        id of a Warp mesh, where the Warp float32 query needs one; see :class:`Flat`)."""
        self.device_values.append((offset, count, resolve))

    def surface(self, offset: int, queries) -> None:
        """A mesh or outline whose numbers (:mod:`ndpack.meshes.layout`, placed by :meth:`params`)
        start at ``offset``.

        The surface's leaf hands over its kernels as data, since the meshes sit above this layer:
        ``queries(program)`` adds the surface queries to the interpreter and returns the name of
        the distance ``name(p, prm, o)``, and adds ``surface_feature``, ``surface_distance_at``
        and ``surface_slope``, which the gradient entries call
        (:func:`ndpack.meshes.kernels.add_interpreter_queries`).
        """
        if self.dim not in (2, 3):
            raise KernelError(f"a surface in {self.dim}-D: meshes are 3-D and outlines 2-D")
        self._surfaces = queries
        self._push(SURFACE, offset)

    def user(self, kernel: Kernel, values) -> None:
        """A user's scalar plug-in ``kernel(p, prm, o)`` on its ``values``; the same code once."""
        for number, known in enumerate(self.users):
            if known is kernel or known.same_code(kernel):
                break
        else:
            number = len(self.users)
            self.users.append(kernel)
        self._push(USER + number, self.params(values))

    def operation(self, opcode: int, constant: float | None = None) -> None:
        """A value operation on the stack's top (see the module docstring)."""
        argument = -1
        if constant is not None:  # constants in the root's units: scaled like the distance
            argument = self.params([constant * self._transforms[-1][2]])
        if opcode in (MIN, MAX, DIFFERENCE, SMOOTH):
            self._height -= 1
        self.instructions.append([opcode, argument, -1])

    @contextlib.contextmanager
    def transformed(self, matrix, shift, factor: float = 1.0):
        """Children added inside see ``q = matrix @ p + shift`` and their distance times ``factor``."""
        a, b, scale, _ = self._transforms[-1]
        matrix = np.asarray(matrix, dtype=np.float64)
        self._transforms.append([matrix @ a, matrix @ b + np.asarray(shift, dtype=np.float64), scale * factor, None])
        try:
            yield
        finally:
            self._transforms.pop()

    # ------------------------------------------------------------------ finishing
    def _push(self, opcode: int, offset: int) -> None:
        self.instructions.append([opcode, offset, self._transform_block()])
        self._height += 1
        self.depth = max(self.depth, self._height)

    def _transform_block(self) -> int:
        """Offset of the current transform's block (written once per context), -1 for none."""
        current = self._transforms[-1]
        a, b, factor, block = current
        if block is None:
            identity = np.array_equal(a, np.eye(self.dim)) and not b.any() and factor == 1.0
            block = current[3] = -1 if identity else self.params([*a.ravel(), *b, factor])
        return block

    def finish(self) -> Flat:
        """The interpreter of this tape's dimension and plug-ins, and the tape's numbers."""
        if self.depth > REGISTERS:
            raise TapeTooDeep(f"the tree needs {self.depth} values at once; the tape holds {REGISTERS}")
        # The interpreter's plug-ins in a canonical order, so a set of plug-ins is one program
        # whatever the tree; the opcodes follow that order.
        order = sorted(range(len(self.users)), key=lambda k: _code_key(self.users[k]))
        renumber = {USER + old: USER + new for new, old in enumerate(order)}
        instructions = np.array([[renumber.get(op, op), arg, t] for op, arg, t in self.instructions], dtype=np.float64)
        start = self._size
        self._chunks.append(instructions.ravel())
        params = np.concatenate(self._chunks)
        params[0] = len(instructions)
        params[2] = start
        only = instructions[0] if len(instructions) == 1 else None
        params[1] = only[1] if only is not None and only[0] == SURFACE and only[2] < 0 else -1
        users = tuple(self.users[k] for k in order)
        surfaces = self._surfaces if (instructions[:, 0] == SURFACE).any() else None
        if params[1] >= 0:  # one untransformed mesh or outline: its queries alone, no interpreter
            return Flat(surface_program(self.dim, surfaces), params, self.device_values)
        return Flat(interpreter(self.dim, users, surfaces), params, self.device_values)


def flatten(shape) -> Flat:
    """The tape of ``shape`` with its interpreter.

    Raises
    ------
    KernelError
        If a part has no scalar kernel (a NumPy-only plug-in); :class:`TapeTooDeep` if the tree
        needs more than :data:`REGISTERS` values at once.
    """
    tape = Tape(shape.dim)
    tape.add(shape)
    return tape.finish()


def _code_key(kernel: Kernel) -> str:
    return hashlib.sha1(kernel._code.encode()).hexdigest()


def interpreter(dim: int, users: tuple = (), surfaces=None) -> Program:
    """The program that evaluates any tape of dimension ``dim`` with the plug-ins ``users``, and
    with meshes (3-D) or outlines (2-D) where ``surfaces`` is given: the function that adds their
    queries (see :meth:`Tape.surface`; there is one, ``ndpack.meshes.kernels.add_interpreter_queries``).

    One per dimension, set of plug-ins and whether with surfaces (cached here, and its compiled
    code on disk): its text holds the library, the surface queries, the plug-ins and the
    interpreter. Surfaces are apart because their queries are most of the code: analytic shapes
    do not wait for them to compile.
    """
    key = (int(dim), tuple(_code_key(kernel) for kernel in users), surfaces is not None)
    if key not in _interpreters:
        _interpreters[key] = _interpreter(int(dim), users, surfaces)
    return _interpreters[key]


_interpreters: dict[tuple, Program] = {}  # (dim, plug-ins' code, with surfaces) -> program


def surface_program(dim: int, surfaces) -> Program:
    """The program of a tape that is one untransformed mesh (3-D) or outline (2-D) alone: the
    surface queries (added by ``surfaces``, see :meth:`Tape.surface`) at ``prm[1]``, without the
    interpreter and the primitives, which such a tape never runs. The entries are the
    interpreter's for that tape, and the numbers the same. A mesh's first packing compiles less:
    with :func:`~ndpack.kernels.compile.cuda_device_function`, numba-cuda's clearance kernel for a
    mesh went from 23,500 PTX lines to 12,200 (``bench/cuda_compile.py``). One per dimension,
    cached here and on disk."""
    key = (int(dim), "alone")
    if key not in _interpreters:
        program = Program(int(dim), {2: "outlines", 3: "meshes"}[int(dim)])
        distance = surfaces(program)
        program.add_functions(_ALONE.replace("SURFACE_DISTANCE", distance))
        _interpreters[key] = program
    return _interpreters[key]


def _interpreter(dim: int, users: tuple, surfaces) -> Program:
    title = f"{dim}-D shapes" + {2: " and outlines", 3: " and meshes"}.get(dim, "") * (surfaces is not None)
    names = ", ".join(kernel.name.removeprefix("user_") for kernel in users)
    program = Program(dim, title + (f", plug-ins {names}" if users else ""))
    cases = []
    for opcode, function in enumerate(LEAVES):
        if ONLY_IN.get(function, dim) == dim:
            cases.append((opcode, program.use(function)))
    if surfaces is not None:
        cases.append((SURFACE, surfaces(program)))
    for number, kernel in enumerate(users):
        cases.append((USER + number, program.add_kernel(kernel.renamed(f"plugin{number}_{kernel.name}"))))
    branches = "".join(f"    if op == {opcode}:\n        return {name}(x, prm, o)\n" for opcode, name in cases)
    for source in (f"def tape_primitive(x, prm, op: int, o: int):\n{branches}    return 0.0\n",
                   _TAPE_LEAF, _sd_source(REGISTERS), NO_GRADIENT if surfaces is None else _GRADIENT):
        program.add_functions(source)
    # Numba calls a function through many arguments (seven per array): the dispatch inlined
    # into sd runs the demo part's distance 1.4-2x as fast (2 cores).
    program.inline.update({"tape_primitive", "tape_leaf"})
    return program


# The leaf at instruction ``at``: its transform applied to the point, then its primitive (one
# call of each, so that the compilers can inline them: see Program.inline).
_TAPE_LEAF = """def tape_leaf(p, prm, at: int):
    op = int(prm[at])
    o = int(prm[at + 1])
    t = int(prm[at + 2])
    x = p
    if t >= 0:
        q = point()
        for j in range(D):
            s = prm[t + D * D + j]
            for i in range(D):
                s += prm[t + j * D + i] * p[i]
            q[j] = s
        x = q
    v = tape_primitive(x, prm, op, o)
    if t >= 0:
        v = prm[t + D * D + D] * v
    return v
"""


def _sd_source(registers: int) -> str:
    """The interpreter's entry ``sd(p, prm)``: the tape's value stack in ``acc`` (its top) and
    ``registers - 1`` scalars ``r0 ...`` below it, indexed by a chain of ifs."""
    below = range(registers - 1)

    def switch(statement):
        return "".join(f"            {'if' if i == 0 else 'elif'} height == {i + 1}:\n"
                       f"                {statement.format(i=i)}\n" for i in below)

    return (
        f"def {ENTRY}(p, prm):\n"
        "    start = int(prm[2])\n"
        "    acc = 0.0\n"
        "    height = 0\n"
        + "".join(f"    r{i} = 0.0\n" for i in below)
        + "    for k in range(int(prm[0])):\n"
        f"        at = start + {WIDTH} * k\n"
        "        op = int(prm[at])\n"
        "        if op >= 0:\n"
        "            v = tape_leaf(p, prm, at)\n"
        + switch("r{i} = acc")
        + "            acc = v\n"
        "            height += 1\n"
        f"        elif op == {NEGATE}:\n"
        "            acc = -acc\n"
        f"        elif op == {OFFSET}:\n"
        "            acc = acc - prm[int(prm[at + 1])]\n"
        f"        elif op == {SHELL}:\n"
        "            acc = abs(acc) - prm[int(prm[at + 1])]\n"
        "        else:\n"
        "            height -= 1\n"
        "            a = 0.0\n"
        + switch("a = r{i}")
        + f"            if op == {MIN}:\n"
        "                acc = min(a, acc)\n"
        f"            elif op == {MAX}:\n"
        "                acc = max(a, acc)\n"
        f"            elif op == {DIFFERENCE}:\n"
        "                acc = max(a, -acc)\n"
        "            else:\n"
        "                blend = prm[int(prm[at + 1])]\n"
        "                h = min(max(0.5 + (acc - a) / (2.0 * blend), 0.0), 1.0)\n"
        "                acc = h * a + (1.0 - h) * acc - blend * h * (1.0 - h)\n"
        "    return acc\n"
    )


# The gradient entries (see ndpack.kernels.program): closed-form where the whole shape is one
# untransformed surface (prm[1] its offset), else none (-1: the backends take differences).
_GRADIENT = f"""def {FEATURE}(p, prm, hint: float, bound: float):
    o = int(prm[1])
    if o < 0:
        return -1.0
    return surface_feature(p, prm, o, hint, bound)


def {AT_FEATURE}(p, prm, f: float):
    o = int(prm[1])
    if o < 0:
        return {ENTRY}(p, prm)
    return surface_distance_at(p, prm, o, f)


def {SLOPE}(p, prm, f: float, value: float, k: int):
    o = int(prm[1])
    if o < 0:
        return 0.0
    return surface_slope(p, prm, o, f, value, k)
"""


# The entries of a surface alone (see surface_program): the interpreter's, where prm[1] >= 0.
_ALONE = f"""def {ENTRY}(p, prm):
    return SURFACE_DISTANCE(p, prm, int(prm[1]))


def {FEATURE}(p, prm, hint: float, bound: float):
    return surface_feature(p, prm, int(prm[1]), hint, bound)


def {AT_FEATURE}(p, prm, f: float):
    return surface_distance_at(p, prm, int(prm[1]), f)


def {SLOPE}(p, prm, f: float, value: float, k: int):
    return surface_slope(p, prm, int(prm[1]), f, value, k)
"""
