"""Device kernels written once, printed for numba-cuda and for Warp.

The GPU backends' kernels that do not depend on how a backend walks a mesh (the prototype
store's selections, splits and tables: :mod:`ndpack.backends.store_kernels`) are written once, in
the numba dialect with typed arguments, and printed here for each backend:

- every argument is annotated with a string of :data:`ARGUMENT_TYPES` (Warp needs the types;
  numba-cuda infers them, so its print drops the annotations);
- a function that calls ``thread()`` is a kernel (``cuda.grid(1)``, ``wp.tid()``): one thread per
  item, which checks its index against the item count itself (numba-cuda rounds a launch up to
  whole blocks); the others are device functions;
- ``atomic_add``, ``atomic_max`` and ``atomic_exch`` (array, index, value) are the backends'
  atomics; ``point()`` is a local point of length ``D``; ``sd(p, prm)`` and ``D`` come from the
  module the text is printed into.

For Warp, which does not promote ints to floats, float constants are cast to the module's float
``F``, ``float(x)`` becomes ``F(x)``, ``math.f`` ``wp.f``, ``min``/``max``/``abs`` Warp's, ``a if
c else b`` ``wp.where(c, a, b)``, and ``x[i, k]`` of a ``points`` array (Warp's array of vectors)
``x[i][k]``. What Warp cannot do is refused here with the function and line named: a local
point is a value in Warp and an array in numba, so a point is never assigned whole to a name nor
written in a function it was passed to; a call's result is unpacked into names, never indexed; a
kernel returns nothing.
"""

from __future__ import annotations

import ast
import copy
import math

from ..errors import KernelError

#: The portable argument types, and Warp's (numba-cuda takes the arrays the host gives).
ARGUMENT_TYPES = {
    "int": "int",
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


def _check(function: ast.FunctionDef, types: dict[str, str]) -> None:
    """Refuse what would mean one thing in numba and another in Warp (see the module's notes)."""
    points = {name for name, kind in types.items() if kind == "point"}
    kernel = is_kernel(function)
    for node in ast.walk(function):
        if isinstance(node, ast.Assign | ast.AugAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if isinstance(target, ast.Subscript) and _name(target.value) in points:
                    _fail(function, node, f"{_name(target.value)!r} is a point passed in: Warp passes it by "
                          "value, so a write would not reach the caller; return the values instead")
                unpacked = (isinstance(target, ast.Tuple) and isinstance(node.value, ast.Call)
                            and all(isinstance(name, ast.Name) for name in target.elts))
                if not (isinstance(target, ast.Name | ast.Subscript) or unpacked):
                    _fail(function, node, "assign to one name or one element at a time, or unpack a call's "
                          "results into names")
            value = getattr(node, "value", None)
            if isinstance(node, ast.Assign) and isinstance(value, ast.Name) and value.id in points:
                _fail(function, node, f"a point ({value.id!r}) is copied element by element (Warp copies a "
                      "point assigned whole, numba shares it)")
        elif isinstance(node, ast.Subscript) and isinstance(node.value, ast.Call):
            _fail(function, node, "unpack a call's results into names (a, b = f(...)) instead of indexing them")
        elif isinstance(node, ast.Return) and kernel and node.value is not None:
            _fail(function, node, "a kernel returns nothing")
        elif isinstance(node, ast.Attribute) and _name(node.value) in ("cuda", "wp", "np", "numba"):
            _fail(function, node, f"{ast.unparse(node)} is a backend's own: use the portable names "
                  f"(thread(), {', '.join(ATOMICS)})")
    # A local point assigned whole to another name (an alias in numba, a copy in Warp).
    made = {target.id for node in ast.walk(function) if isinstance(node, ast.Assign)
            for target in node.targets
            if isinstance(target, ast.Name) and isinstance(node.value, ast.Call) and _name(node.value.func) == "point"}
    for node in ast.walk(function):
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Name) and node.value.id in made:
            _fail(function, node, f"a point ({node.value.id!r}) is copied element by element (Warp copies a "
                  "point assigned whole, numba shares it)")


class _ToCuda(ast.NodeTransformer):
    def visit_Call(self, node):
        self.generic_visit(node)
        name = _name(node.func)
        if name == "thread":
            return ast.parse("cuda.grid(1)", mode="eval").body
        if name in ATOMICS:
            node.func = ast.parse(ATOMICS[name][0], mode="eval").body
        return node


class _ToWarp(ast.NodeTransformer):
    def __init__(self, types: dict[str, str]):
        self.types = types

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
        if name in ATOMICS:
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
    docstrings (the comments are the source's)."""
    if dialect not in ("numba", "cuda", "warp"):
        raise KernelError(f"dialect must be 'numba', 'cuda' or 'warp', got {dialect!r}")
    printed = []
    for function in _parse(text):
        types = _argument_types(function)
        _check(function, types)
        if dialect == "numba":
            for name in ("thread", *ATOMICS):
                if _calls(function, name):
                    _fail(function, function, f"{name}() needs a GPU dialect ('cuda' or 'warp')")
        function = copy.deepcopy(function)
        if dialect != "warp":
            for arg in function.args.args:
                arg.annotation = None
            function = _ToCuda().visit(function)
            printed.append(ast.unparse(function))
            continue
        for arg in function.args.args:
            arg.annotation = ast.parse(ARGUMENT_TYPES[types[arg.arg]], mode="eval").body
        decorator = "wp.kernel" if is_kernel(function) else "wp.func"
        function = _ToWarp(types).visit(function)
        function.decorator_list = [ast.parse(decorator, mode="eval").body]
        printed.append(ast.unparse(function))
    return "\n\n\n".join(printed) + "\n"
