"""Device kernels written once, printed for Numba (CPU and CUDA) and for Warp.

The compiled backends' own kernels (the move and its converge, the sphere index's queries, the
prototype store's selections, splits and tables: :mod:`ndpack.backends.move_kernels`,
:mod:`ndpack.backends.index_kernels`, :mod:`ndpack.backends.store_kernels`) are written once, in the
numba dialect with typed arguments, and printed here for each backend:

- every argument is annotated with a string of :data:`ARGUMENT_TYPES` (Warp needs the types;
  Numba infers them, so its print drops the annotations);
- a function that calls ``thread()`` is a kernel (``cuda.grid(1)``, ``wp.tid()``): one thread per
  item, which checks its index against the item count itself (numba-cuda rounds a launch up to
  whole blocks); the others are device functions;
- ``atomic_add``, ``atomic_max`` and ``atomic_exch`` (array, index, value) are the backends'
  atomics; ``u64(x)`` a 64-bit unsigned int (for hashes); ``point()`` a local point of length
  ``D``; ``sd(p, prm)`` (and the program's other functions) and ``D`` come from the module the
  text is printed into.

A point is an array in Numba and a value (``VecD``) in Warp, which keeps it in registers. A
function that writes a point it was given (directly or through a function it passes it to)
therefore returns it in Warp, after its own results, and every call of it assigns the point
back: ``c = f(x, g)`` is printed ``c, x, g = f(x, g)``. So that this means what Numba means, a
point is never assigned whole (``q = p``: an alias in Numba, a copy in Warp), a function that
writes points is called as a statement with plain names for them (``c = f(x, g)``, ``f(x, g)``),
never the same point twice, and a call's results are unpacked into names, never indexed.

For Warp, which does not promote ints to floats, float constants are cast to the module's float
``F``, ``float(x)`` becomes ``F(x)``, ``math.f`` ``wp.f``, ``min``/``max``/``abs`` Warp's, ``a if
c else b`` ``wp.where(c, a, b)``, ``x[i, k]`` of a ``points`` array (Warp's array of vectors)
``x[i][k]``, and a name given an int constant ``int(...)`` (a variable, which a loop may change).
What Warp cannot do is refused here with the function and line named.
"""

from __future__ import annotations

import ast
import copy
import math

from ..errors import KernelError

#: The portable argument types, and Warp's (numba-cuda takes the arrays the host gives).
ARGUMENT_TYPES = {
    "int": "int",
    "bool": "bool",
    "u64": "wp.uint64",
    "float": "F",
    "ints": "wp.array(dtype=wp.int32)",
    "floats": "wp.array(dtype=F)",
    "points": "wp.array(dtype=VecD)",
    "int_table": "wp.array2d(dtype=wp.int32)",
    "point": "VecD",
}
#: The atomics a kernel may call: numba-cuda's and Warp's names.
ATOMICS = {
    "atomic_add": ("cuda.atomic.add", "wp.atomic_add"),
    "atomic_max": ("cuda.atomic.max", "wp.atomic_max"),
    "atomic_exch": ("cuda.atomic.exch", "wp.atomic_exch"),
}
_WARP_BUILTINS = {"min": "wp.min", "max": "wp.max", "abs": "wp.abs"}


def _fail(function: ast.FunctionDef, node: ast.AST, message: str):
    line = getattr(node, "lineno", function.lineno)
    raise KernelError(f"portable kernel {function.name!r}, line {line}: {message}")


def _name(node: ast.AST) -> str | None:
    return node.id if isinstance(node, ast.Name) else None


def _parse(text: str) -> list[ast.FunctionDef]:
    tree = ast.parse(text)
    return [node for node in tree.body if isinstance(node, ast.FunctionDef)]


def _argument_types(function: ast.FunctionDef) -> dict[str, str]:
    types = {}
    for arg in function.args.args:
        annotation = arg.annotation
        if not (isinstance(annotation, ast.Constant) and annotation.value in ARGUMENT_TYPES):
            _fail(function, arg, f"argument {arg.arg!r} needs one of the types {sorted(ARGUMENT_TYPES)}, "
                  "as a string annotation")
        types[arg.arg] = annotation.value
    return types


def _calls(function: ast.FunctionDef, name: str) -> bool:
    return any(isinstance(node, ast.Call) and _name(node.func) == name for node in ast.walk(function))


def is_kernel(function: ast.FunctionDef) -> bool:
    """Whether ``function`` is a kernel (it calls ``thread()``), not a device function."""
    return _calls(function, "thread")


def kernel_names(text: str) -> list[str]:
    """The names of the kernels (not the device functions) of portable ``text``."""
    return [function.name for function in _parse(text) if is_kernel(function)]


def kernel_argument_types(text: str) -> dict[str, tuple[str, ...]]:
    """The kernels of portable ``text`` by name, each with its arguments' types in order (the
    annotations, names of :data:`ARGUMENT_TYPES`): what a compiler given a signature needs."""
    return {function.name: tuple(_argument_types(function).values()) for function in _parse(text)
            if is_kernel(function)}


def _points(function: ast.FunctionDef) -> set[str]:
    """The names of ``function``'s points: its arguments typed ``point`` and the locals made by ``point()``."""
    names = {arg.arg for arg in function.args.args
             if isinstance(arg.annotation, ast.Constant) and arg.annotation.value == "point"}
    for node in ast.walk(function):
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Call) and _name(node.value.func) == "point":
            names.update(target.id for target in node.targets if isinstance(target, ast.Name))
    return names


def _arity(function: ast.FunctionDef) -> int:
    """How many values ``function`` returns (0: none)."""
    for node in ast.walk(function):
        if isinstance(node, ast.Return) and node.value is not None:
            return len(node.value.elts) if isinstance(node.value, ast.Tuple) else 1
    return 0


def written_points(functions: list[ast.FunctionDef]) -> dict[str, list[int]]:
    """Per function, the positions of the point arguments it writes: directly (``p[k] = ...``) or
    by passing them to a function that writes them (to a fixed point)."""
    direct, calls, arguments = {}, {}, {}
    for function in functions:  # each function's summary, walked once
        names = [arg.arg for arg in function.args.args]
        points = _points(function)
        arguments[function.name] = [name if name in points else None for name in names]
        direct[function.name] = {_name(target.value) for node in ast.walk(function)
                                 if isinstance(node, ast.Assign | ast.AugAssign)
                                 for target in (node.targets if isinstance(node, ast.Assign) else [node.target])
                                 if isinstance(target, ast.Subscript)}
        calls[function.name] = [(_name(node.func), [_name(arg) for arg in node.args]) for node in ast.walk(function)
                                if isinstance(node, ast.Call) and _name(node.func) in arguments]
    writes: dict[str, set[int]] = {function.name: set() for function in functions}
    changed = True
    while changed:
        changed = False
        for name, own in arguments.items():
            written = set(direct[name])
            for callee, passed in calls[name]:
                if callee in writes:
                    written.update(passed[k] for k in writes[callee] if k < len(passed))
            positions = {k for k, argument in enumerate(own) if argument is not None and argument in written}
            if positions - writes[name]:
                writes[name] |= positions
                changed = True
    return {name: sorted(positions) for name, positions in writes.items()}


def _check(function: ast.FunctionDef, types: dict[str, str], writes: dict[str, list[int]]) -> None:
    """Refuse what would mean one thing in numba and another in Warp (see the module's notes)."""
    points = _points(function)
    kernel = is_kernel(function)
    statements = {id(node.value) for node in ast.walk(function) if isinstance(node, ast.Expr | ast.Assign)}
    for node in ast.walk(function):
        if isinstance(node, ast.Call) and writes.get(_name(node.func)):
            passed = [node.args[k] for k in writes[_name(node.func)] if k < len(node.args)]
            if id(node) not in statements:
                _fail(function, node, f"{_name(node.func)}() writes points it is given: call it as a statement "
                      "(c = f(...) or f(...)), not inside an expression")
            if not all(isinstance(arg, ast.Name) and arg.id in points for arg in passed):
                _fail(function, node, f"{_name(node.func)}() writes points it is given: pass them as names of "
                      "points (made by point() or passed in)")
            if len({arg.id for arg in passed}) < len(passed):
                _fail(function, node, f"{_name(node.func)}() is given one point twice where it writes them")
        if isinstance(node, ast.Assign | ast.AugAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                names = target.elts if isinstance(target, ast.Tuple) else [target]
                creating = isinstance(node, ast.Assign) and isinstance(node.value, ast.Call) and _name(
                    node.value.func) == "point"
                if any(_name(name) in points for name in names) and not creating:
                    _fail(function, node, "a point is assigned whole (an alias in numba, a copy in Warp): "
                          "copy it element by element")
                unpacked = (isinstance(target, ast.Tuple) and isinstance(node.value, ast.Call)
                            and all(isinstance(name, ast.Name) for name in target.elts))
                if not (isinstance(target, ast.Name | ast.Subscript) or unpacked):
                    _fail(function, node, "assign to one name or one element at a time, or unpack a call's "
                          "results into names")
            value = getattr(node, "value", None)
            if isinstance(node, ast.Assign) and isinstance(value, ast.Name) and value.id in points:
                _fail(function, node, f"a point ({value.id!r}) is assigned whole (an alias in numba, a copy in "
                      "Warp): copy it element by element")
        elif isinstance(node, ast.Subscript) and isinstance(node.value, ast.Call):
            _fail(function, node, "unpack a call's results into names (a, b = f(...)) instead of indexing them")
        elif isinstance(node, ast.Return) and kernel and node.value is not None:
            _fail(function, node, "a kernel returns nothing")
        elif isinstance(node, ast.Attribute) and _name(node.value) in ("cuda", "wp", "np", "numba"):
            _fail(function, node, f"{ast.unparse(node)} is a backend's own: use the portable names "
                  f"(thread(), {', '.join(ATOMICS)})")


class _ToCuda(ast.NodeTransformer):
    def visit_Call(self, node):
        self.generic_visit(node)
        name = _name(node.func)
        if name == "thread":
            return ast.parse("cuda.grid(1)", mode="eval").body
        if name in ATOMICS:
            node.func = ast.parse(ATOMICS[name][0], mode="eval").body
        elif name == "u64":
            node.func = ast.parse("np.uint64", mode="eval").body
        return node


class _ToWarp(ast.NodeTransformer):
    def __init__(self, types: dict[str, str], writes: dict[str, list[int]], arity: dict[str, int],
                 returned: list[str]):
        self.types, self.writes, self.arity = types, writes, arity
        self.returned = returned  # the points this function writes, returned after its results
        self.spare = 0

    def _written_back(self, call: ast.Call) -> list[ast.expr]:
        """The names of the points ``call`` writes (assigned back in Warp)."""
        return [ast.Name(_name(call.args[k]), ast.Store()) for k in self.writes.get(_name(call.func), ())
                if k < len(call.args)]

    def _unused(self) -> ast.Name:
        self.spare += 1
        return ast.Name(f"unused_{self.spare}", ast.Store())

    def visit_Expr(self, node):
        if isinstance(node.value, ast.Call) and self.writes.get(_name(node.value.func)):
            results = [self._unused() for _ in range(self.arity.get(_name(node.value.func), 0))]
            return self.visit(ast.copy_location(ast.Assign(targets=[ast.Tuple(results, ast.Store())],
                                                           value=node.value), node))
        return self.generic_visit(node)

    def visit_Return(self, node):
        self.generic_visit(node)
        if not self.returned:
            return node
        values = [] if node.value is None else (node.value.elts if isinstance(node.value, ast.Tuple) else [node.value])
        values = [*values, *(ast.Name(name, ast.Load()) for name in self.returned)]
        node.value = values[0] if len(values) == 1 else ast.Tuple(values, ast.Load())
        return node

    @staticmethod
    def _expression(text: str) -> ast.expr:
        return ast.parse(text, mode="eval").body

    def _float(self, value: ast.expr) -> ast.expr:
        return ast.Call(func=ast.Name("F", ast.Load()), args=[value], keywords=[])

    def visit_Constant(self, node):
        if isinstance(node.value, float):
            return self._float(node)
        return node

    def visit_Attribute(self, node):
        if _name(node.value) == "math":
            if node.attr in ("inf", "nan"):
                return self._float(self._expression(f"wp.{node.attr}"))
            if node.attr in ("pi", "e"):
                return self._float(ast.Constant(getattr(math, node.attr)))
        return self.generic_visit(node)

    def visit_Call(self, node):
        name = _name(node.func)
        if name == "float":  # its argument is cast whole: no constant in it is cast first
            # Warp's cast of a bare name retypes the name itself (F(k) makes k a float for the
            # rest of the function: range(k) and x[k] then fail), so a name is cast as +k.
            node.args = [ast.UnaryOp(ast.UAdd(), arg) if isinstance(arg, ast.Name) else self.visit(arg)
                         for arg in node.args]
            node.func = ast.Name("F", ast.Load())
            return node
        self.generic_visit(node)
        if name == "thread":
            return self._expression("wp.tid()")
        if name == "point":
            return self._expression("VecD()")
        if name == "u64":
            node.func = self._expression("wp.uint64")
        elif name in ATOMICS:
            node.func = self._expression(ATOMICS[name][1])
        elif name in _WARP_BUILTINS:
            node.func = self._expression(_WARP_BUILTINS[name])
            while len(node.args) > 2:  # Warp's min and max take two
                node.args = [ast.Call(func=copy.deepcopy(node.func), args=node.args[:2], keywords=[]),
                             *node.args[2:]]
        elif isinstance(node.func, ast.Attribute) and _name(node.func.value) == "math":
            node.func = self._expression(f"wp.{node.func.attr}")
        return node

    def visit_Assign(self, node):
        if isinstance(node.value, ast.Call) and self.writes.get(_name(node.value.func)):
            back = self._written_back(node.value)
            target = node.targets[0]
            targets = [*(target.elts if isinstance(target, ast.Tuple) else [target]), *back]
            node.targets = [targets[0] if len(targets) == 1 else ast.Tuple(targets, ast.Store())]
        self.generic_visit(node)
        value = node.value
        if isinstance(value, ast.UnaryOp) and isinstance(value.op, ast.USub):
            value = value.operand
        if isinstance(value, ast.Constant) and type(value.value) is int:
            # A name given a constant is a constant to Warp, which refuses to change it in a loop
            # it keeps (not unrolled): int(0) declares a variable.
            node.value = ast.Call(func=ast.Name("int", ast.Load()), args=[node.value], keywords=[])
        return node

    def visit_IfExp(self, node):
        self.generic_visit(node)
        return ast.Call(func=self._expression("wp.where"), args=[node.test, node.body, node.orelse], keywords=[])

    def visit_Subscript(self, node):
        self.generic_visit(node)
        if self.types.get(_name(node.value)) == "points" and isinstance(node.slice, ast.Tuple):
            row, column = node.slice.elts
            inner = ast.Subscript(value=node.value, slice=row, ctx=ast.Load())
            return ast.Subscript(value=inner, slice=column, ctx=node.ctx)
        return node


def render(text: str, dialect: str) -> str:
    """Portable ``text`` (functions in the subset above) printed for ``dialect``: ``"numba"`` (a
    Numba module for the CPU or CUDA that defines ``D``, ``point()`` and ``sd``; device functions
    only), ``"cuda"`` (numba-cuda: the same, which imports ``cuda``, kernels too) or ``"warp"`` (a
    Warp module that defines ``F``, ``D``, ``VecD`` and ``sd``): functions only, with their
    docstrings (the comments are the source's). The functions that write points must be in the
    same ``text`` as their callers."""
    if dialect not in ("numba", "cuda", "warp"):
        raise KernelError(f"dialect must be 'numba', 'cuda' or 'warp', got {dialect!r}")
    functions = _parse(text)
    writes = written_points(functions)
    arity = {function.name: _arity(function) for function in functions}
    printed = []
    for function, copied in zip(functions, _parse(text)):  # a second parse to print from: faster than a deepcopy
        types = _argument_types(function)
        _check(function, types, writes)
        if dialect == "numba":
            for name in ("thread", *ATOMICS):
                if _calls(function, name):
                    _fail(function, function, f"{name}() needs a GPU dialect ('cuda' or 'warp')")
        function = copied
        if dialect != "warp":
            for arg in function.args.args:
                arg.annotation = None
            function = _ToCuda().visit(function)
            printed.append(ast.unparse(function))
            continue
        for arg in function.args.args:
            arg.annotation = ast.parse(ARGUMENT_TYPES[types[arg.arg]], mode="eval").body
        decorator = "wp.kernel" if is_kernel(function) else "wp.func"
        returned = [function.args.args[k].arg for k in writes[function.name]]
        if returned and not _always_returns(function.body):  # a procedure: it returns the points it wrote
            function.body.append(ast.Return(value=None))
        function = _ToWarp(types, writes, arity, returned).visit(function)
        function.decorator_list = [ast.parse(decorator, mode="eval").body]
        printed.append(ast.unparse(ast.fix_missing_locations(function)))
    return "\n\n\n".join(printed) + "\n"


def _always_returns(statements) -> bool:
    """Whether every path through ``statements`` ends in a return."""
    if not statements:
        return False
    last = statements[-1]
    if isinstance(last, ast.Return):
        return True
    if isinstance(last, ast.If):
        return _always_returns(last.body) and _always_returns(last.orelse)
    return False
