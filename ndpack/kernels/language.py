"""The scalar kernel language: one Python source, printed for Numba (CPU and CUDA) and Warp.

Every shape's distance is written once as plain Python functions in a small subset, which this
module checks, types, and prints in the dialect each compiler accepts. The same subset is what
users write scalar plug-ins in (:class:`ndpack.ScalarFunction`).

The subset
----------
- A function ``def f(p, prm, ...)``: ``p`` is a point (``p[i]`` for ``0 <= i < D``), ``prm`` a
  flat array of float parameters; more arguments may be annotated ``int`` or ``float``. It
  returns one float.
- ``D``, the dimension, is a compile-time constant.
- Statements: ``x = e``, ``x += e`` (and ``-= *= /=``), ``q[i] = e`` on a local point,
  ``for i in range(...)``, ``while``, ``if``/``elif``/``else``, ``break``, ``continue``,
  ``return e``, ``pass``.
- Expressions: int, float and bool constants; ``+ - * / // % **``; comparisons; ``and or
  not``; ``a if c else b``; ``math.<f>(...)`` for the functions in :data:`MATH_FUNCTIONS`,
  ``math.pi`` and ``math.e``; ``min``, ``max``, ``abs``, ``int``, ``float``; ``point()``, a
  new local point of length ``D``; ``stack()``, a new local array of :data:`STACK_DEPTH` ints
  (for tree traversals: ``s[i] = n``, ``n = s[i]``); calls of other kernel functions.
- Not allowed: other globals, lists, tuples, strings, attributes, ``inf`` (use a large number).
- Every path through the function ends in ``return``.

Arithmetic means what it means in Python on every backend: ``//`` rounds down and ``%`` takes
the sign of the divisor, for ints and floats alike (Warp's own operators follow C, so the Warp
dialect calls the helpers of :func:`warp_prelude`); ``**`` always gives a float (as ``float(a)
** float(b)``: ``2 ** -1`` is 0.5, ``2 ** 3`` is 8.0). A constant index of the point, of a
``point()`` or of a ``stack()`` must lie in the array (checked when the kernel is printed, or
when a scalar plug-in is made); other indices are not checked, so they must stay in range.

Dialects
--------
``"numba"``: for ``numba.njit``; ``point()`` is ``np.empty(D)``.
``"cuda"``: for ``numba.cuda.jit(device=True)``; ``point()`` is a local array.
``"warp"``: ``@wp.func`` with typed arguments; float constants and int operands in float
arithmetic are cast explicitly (Warp does not promote), ``math.f`` becomes ``wp.f``, ``a ** b``
becomes ``wp.pow``, ``//`` and ``%`` call the helpers of :func:`warp_prelude`.

Error messages name the function as written and the line in its file (for source text, the
line counted from the ``def``).
"""

from __future__ import annotations

import ast
import copy
import inspect
import math
import operator
import re
import textwrap

from ..errors import KernelError

#: ``math`` functions the kernel language accepts (Warp has each as ``wp.<name>``).
MATH_FUNCTIONS = frozenset(
    "sqrt sin cos tan asin acos atan atan2 exp log log2 log10 sinh cosh tanh floor ceil fabs pow".split()
)
#: ``math`` constants, inlined as numbers.
MATH_CONSTANTS = {"pi": math.pi, "e": math.e}
BUILTINS = frozenset({"min", "max", "abs", "int", "float", "range", "point", "stack"})
#: Length of the int array ``stack()`` makes: a traversal of a balanced tree of 2^32 leaves.
STACK_DEPTH = 64

INT, FLOAT, BOOL, POINT, ARRAY, STACK = "int", "float", "bool", "point", "array", "stack"
#: Types of names that hold arrays (indexable, never numbers).
_ARRAYS = (POINT, ARRAY, STACK)

_BINARY = (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.FloorDiv, ast.Mod, ast.Pow)
_UNARY = (ast.USub, ast.UAdd, ast.Not)
_COMPARE = (ast.Lt, ast.LtE, ast.Gt, ast.GtE, ast.Eq, ast.NotEq)


def parse_function(fn) -> ast.FunctionDef:
    """The AST of a Python function (or of source text holding one function).

    For a function object the line numbers are those of its file, which the syntax tree keeps
    in ``ndpack_file`` (None for source text, whose lines count from the ``def``); the name it
    is reported by is kept in ``ndpack_label`` (a kernel may be renamed, the label stays). An
    ``ast.FunctionDef`` is returned as it is.
    """
    if isinstance(fn, ast.FunctionDef):
        return fn
    filename, first = None, 1
    if isinstance(fn, str):
        source = fn
        where = "kernel source"
    else:
        name = getattr(fn, "__name__", repr(fn))
        if name == "<lambda>":
            raise KernelError(
                "a scalar kernel cannot be a lambda: define it with def (def f(p, params): ...) "
                "in a file or notebook cell"
            )
        try:
            lines, first = inspect.getsourcelines(fn)
        except (OSError, TypeError) as error:
            raise KernelError(
                f"cannot read the source of {name!r} ({error}); define scalar "
                "kernels with def in a file or notebook cell, not with lambda or exec"
            ) from None
        source = "".join(lines)
        filename = inspect.getsourcefile(fn) or inspect.getfile(fn)
        where = f"{fn.__qualname__} ({filename})"
    try:
        tree = ast.parse(textwrap.dedent(source))
    except SyntaxError as error:
        raise KernelError(f"{where}: cannot parse its source ({error.msg})") from None
    functions = [node for node in tree.body if isinstance(node, ast.FunctionDef)]
    if len(functions) != 1:
        raise KernelError(f"{where}: expected exactly one function definition")
    function = functions[0]
    if filename is not None:
        ast.increment_lineno(function, max(first, 1) - 1)  # lines of the file
    function.decorator_list = []
    function.returns = None
    function.ndpack_file = filename
    function.ndpack_label = function.name
    return function


def located_error(function: ast.FunctionDef, node: ast.AST, message: str) -> KernelError:
    """A :class:`KernelError` naming ``function`` as its author wrote it and the line of ``node``."""
    line = getattr(node, "lineno", None) or function.lineno
    filename = getattr(function, "ndpack_file", None)
    where = f"line {line} of {filename}" if filename else f"line {line - function.lineno + 1}"
    return KernelError(
        f"kernel {_label(function)!r}, {where}: {message} (see ndpack.kernels.language for the supported subset)"
    )


def _label(function: ast.FunctionDef) -> str:
    """The function's name as its author wrote it (kept when a kernel is renamed)."""
    return getattr(function, "ndpack_label", function.name)


_FOLD = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.FloorDiv: operator.floordiv,
         ast.Mod: operator.mod}


def constant_int(node: ast.AST, dim: int):
    """The value of an int expression made of constants and ``D`` (= ``dim``), else None."""
    if isinstance(node, ast.Constant):
        return node.value if type(node.value) is int else None
    if isinstance(node, ast.Name):
        return dim if node.id == "D" else None
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        value = constant_int(node.operand, dim)
        if value is None:
            return None
        return -value if isinstance(node.op, ast.USub) else value
    if isinstance(node, ast.BinOp) and type(node.op) in _FOLD:
        left, right = constant_int(node.left, dim), constant_int(node.right, dim)
        if left is None or right is None or (right == 0 and isinstance(node.op, (ast.FloorDiv, ast.Mod))):
            return None
        return _FOLD[type(node.op)](left, right)
    return None


def _always_returns(statements) -> bool:
    """Whether every path through ``statements`` ends in ``return`` (or loops for ever)."""
    for statement in statements:
        if isinstance(statement, ast.Return):
            return True
        if isinstance(statement, ast.If) and _always_returns(statement.body) and _always_returns(statement.orelse):
            return True
        if (isinstance(statement, ast.While) and isinstance(statement.test, ast.Constant)
                and statement.test.value and not _breaks(statement.body)):  # while True, while 1
            return True
    return False


def _breaks(statements) -> bool:
    """Whether a ``break`` in ``statements`` (not in a loop inside them) leaves their loop."""
    for statement in statements:
        if isinstance(statement, ast.Break):
            return True
        if isinstance(statement, ast.If) and (_breaks(statement.body) or _breaks(statement.orelse)):
            return True
    return False


class Signature:
    """Argument types of a kernel function: the point, the parameter array, then int/float extras."""

    def __init__(self, function: ast.FunctionDef):
        args = function.args
        if args.vararg or args.kwarg or args.kwonlyargs or args.defaults or args.posonlyargs:
            raise KernelError(f"kernel {_label(function)!r}: only plain positional arguments are allowed")
        names = [a.arg for a in args.args]
        if len(names) < 2:
            raise KernelError(
                f"kernel {_label(function)!r} must take at least (p, prm): the point and the parameters"
            )
        self.names = names
        self.types = [POINT, ARRAY]
        for a in args.args[2:]:
            kind = getattr(a.annotation, "id", None)
            if kind not in (INT, FLOAT):
                raise KernelError(
                    f"kernel {_label(function)!r}: argument {a.arg!r} needs an annotation, int or float"
                )
            self.types.append(kind)


def _fail(function: ast.FunctionDef, node: ast.AST, message: str):
    raise located_error(function, node, message)


def _arithmetic_kind(op: ast.operator, kinds) -> str:
    """The type of ``a op b`` for operands of types ``kinds``: ``/`` and ``**`` give floats."""
    if isinstance(op, (ast.Div, ast.Pow)) or FLOAT in kinds:
        return FLOAT
    return INT


class _Checker(ast.NodeVisitor):
    """Rejects everything outside the subset and infers the type of every local name."""

    def __init__(self, function: ast.FunctionDef, callees: set[str]):
        self.function = function
        self.callees = callees
        self.signature = Signature(function)
        self.types = dict(zip(self.signature.names, self.signature.types))
        self.changed = False

    def fail(self, node, message):
        _fail(self.function, node, message)

    def run(self) -> dict[str, str]:
        body = self.function.body
        if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
            body = body[1:]  # docstring
        # Types only widen (int -> float), so a few passes reach the fixed point.
        for _ in range(8):
            self.changed = False
            for statement in body:
                self.statement(statement)
            if not self.changed:
                break
        if not _always_returns(body):
            last = body[-1] if body else self.function
            self.fail(last, "a path through the function ends here without return; every path must "
                      "return a number (add a return at the end, or an else that returns)")
        return self.types

    # ---------------------------------------------------------------- statements
    def assign_name(self, node, name, kind):
        if name == "D" or name in self.signature.names[:2]:
            self.fail(node, f"cannot assign to {name!r}")
        if name in _WARP_HELPERS:
            self.fail(node, f"the name {name!r} is reserved")
        old = self.types.get(name)
        if old in _ARRAYS or kind in _ARRAYS:
            if old is not None and old != kind:
                self.fail(node, f"{name!r} cannot be both an array ({old if old in _ARRAYS else kind}) and "
                          "something else")
            new = kind
        elif old is None:
            new = kind
        else:
            new = FLOAT if FLOAT in (old, kind) else old
        if new != old:
            self.types[name] = new
            self.changed = True

    def statement(self, node):
        if isinstance(node, ast.Assign):
            if len(node.targets) != 1:
                self.fail(node, "one assignment target at a time")
            self.assign(node, node.targets[0], self.expr(node.value))
        elif isinstance(node, ast.AugAssign):
            if not isinstance(node.op, _BINARY):
                self.fail(node, f"operator {type(node.op).__name__} is not supported")
            kind = self.expr(node.value)
            if isinstance(node.target, ast.Name):
                current = self.types.get(node.target.id)
                if current is None:
                    self.fail(node, f"{node.target.id!r} is used before it is assigned")
                kind = _arithmetic_kind(node.op, {current if current in (INT, FLOAT) else FLOAT, kind})
            elif isinstance(node.target, ast.Subscript) and isinstance(node.target.value, ast.Name):
                element = INT if self.types.get(node.target.value.id) == STACK else FLOAT
                kind = _arithmetic_kind(node.op, {element, kind})
            self.assign(node, node.target, kind)
        elif isinstance(node, ast.For):
            if node.orelse:
                self.fail(node, "for ... else is not supported")
            if not isinstance(node.target, ast.Name):
                self.fail(node, "the loop variable must be a single name")
            call = node.iter
            if not (isinstance(call, ast.Call) and getattr(call.func, "id", None) == "range"
                    and 1 <= len(call.args) <= 3 and not call.keywords):
                self.fail(node, "loops must run over range(...)")
            for arg in call.args:
                if self.expr(arg) != INT:
                    self.fail(arg, "range() takes ints; wrap the value in int()")
            self.assign_name(node, node.target.id, INT)
            for statement in node.body:
                self.statement(statement)
        elif isinstance(node, ast.While):
            if node.orelse:
                self.fail(node, "while ... else is not supported")
            self.expr(node.test)
            for statement in node.body:
                self.statement(statement)
        elif isinstance(node, ast.If):
            self.expr(node.test)
            for statement in node.body + node.orelse:
                self.statement(statement)
        elif isinstance(node, ast.Return):
            if node.value is None:
                self.fail(node, "return a float")
            if self.expr(node.value) not in (INT, FLOAT):
                self.fail(node, "return a number")
        elif isinstance(node, (ast.Break, ast.Continue, ast.Pass)):
            pass
        elif isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str):
            pass  # a string used as a comment
        else:
            self.fail(node, f"statement {type(node).__name__} is not supported")

    def assign(self, node, target, kind):
        if isinstance(target, ast.Name):
            self.assign_name(node, target.id, kind)
        elif isinstance(target, ast.Subscript) and isinstance(target.value, ast.Name):
            base = self.types.get(target.value.id)
            if base not in (POINT, STACK) or target.value.id == self.signature.names[0]:
                self.fail(node, "only local points made with point() and stacks made with stack() can be "
                          "assigned into")
            if self.expr(target.slice) != INT:
                self.fail(node, "indices must be ints")
            if base == STACK and kind != INT:
                self.fail(node, "a stack holds ints; wrap the value in int()")
            if kind not in (INT, FLOAT):
                self.fail(node, "a point's coordinates are numbers")
        else:
            self.fail(node, "assign to a name or to q[i] of a local point")

    # ---------------------------------------------------------------- expressions
    def expr(self, node) -> str:
        """The type of an expression, also kept on the node (``node.kind``) for the printers.

        The last pass of :meth:`run` sees the final types of every name, so what stays on the
        nodes is final.
        """
        node.kind = self._expr(node)
        return node.kind

    def _expr(self, node) -> str:
        if isinstance(node, ast.Constant):
            value = node.value
            if isinstance(value, bool):
                return BOOL
            if isinstance(value, int):
                return INT
            if isinstance(value, float):
                if not math.isfinite(value):
                    self.fail(node, "constants must be finite; use a large number for infinity")
                return FLOAT
            self.fail(node, f"constant {value!r} is not a number")
        if isinstance(node, ast.Name):
            if node.id == "D":
                return INT
            if node.id not in self.types:
                if node.id in self.callees or node.id == "math":
                    self.fail(node, f"{node.id!r} can only be called")
                self.fail(
                    node, f"unknown name {node.id!r}: kernels see only their arguments, locals and D; "
                    "pass other values through the parameters"
                )
            return self.types[node.id]
        if isinstance(node, ast.Subscript):
            base = node.value
            if not (isinstance(base, ast.Name) and self.types.get(base.id) in _ARRAYS):
                self.fail(node, "only the point, the parameters, local points and stacks can be indexed")
            if isinstance(node.slice, ast.Slice) or self.expr(node.slice) != INT:
                self.fail(node, "indices must be single ints (no slices); wrap floats in int()")
            return INT if self.types[base.id] == STACK else FLOAT
        if isinstance(node, ast.BinOp):
            if not isinstance(node.op, _BINARY):
                self.fail(node, f"operator {type(node.op).__name__} is not supported")
            kinds = {self.expr(node.left), self.expr(node.right)}
            if not kinds <= {INT, FLOAT}:
                self.fail(node, "arithmetic needs numbers")
            return _arithmetic_kind(node.op, kinds)
        if isinstance(node, ast.UnaryOp):
            if not isinstance(node.op, _UNARY):
                self.fail(node, f"operator {type(node.op).__name__} is not supported")
            kind = self.expr(node.operand)
            return BOOL if isinstance(node.op, ast.Not) else kind
        if isinstance(node, ast.BoolOp):
            for value in node.values:
                self.expr(value)
            return BOOL
        if isinstance(node, ast.Compare):
            if not all(isinstance(op, _COMPARE) for op in node.ops):
                self.fail(node, "only < <= > >= == != comparisons are supported")
            for value in [node.left, *node.comparators]:
                if self.expr(value) not in (INT, FLOAT):
                    self.fail(node, "comparisons need numbers")
            return BOOL
        if isinstance(node, ast.IfExp):
            self.expr(node.test)
            kinds = {self.expr(node.body), self.expr(node.orelse)}
            if not kinds <= {INT, FLOAT}:
                self.fail(node, "both sides of a conditional expression must be numbers")
            return FLOAT if FLOAT in kinds else INT
        if isinstance(node, ast.Attribute):
            if isinstance(node.value, ast.Name) and node.value.id == "math" and node.attr in MATH_CONSTANTS:
                return FLOAT
            self.fail(node, "attributes are not supported (except math.pi and math.e)")
        if isinstance(node, ast.Call):
            return self.call(node)
        self.fail(node, f"{type(node).__name__} is not supported")

    def call(self, node) -> str:
        if node.keywords:
            self.fail(node, "keyword arguments are not supported")
        kinds = [self.expr(arg) for arg in node.args]
        func = node.func
        if isinstance(func, ast.Attribute):
            if not (isinstance(func.value, ast.Name) and func.value.id == "math" and func.attr in MATH_FUNCTIONS):
                self.fail(node, f"only math.<f> for f in {sorted(MATH_FUNCTIONS)} can be called")
            return FLOAT
        if not isinstance(func, ast.Name):
            self.fail(node, "call functions by name")
        name = func.id
        if name in ("min", "max", "abs"):
            if not kinds or (name == "abs") != (len(kinds) == 1) or not set(kinds) <= {INT, FLOAT}:
                self.fail(node, f"{name}() takes {'one number' if name == 'abs' else 'two or more numbers'}")
            return FLOAT if FLOAT in kinds else INT
        if name in ("int", "float"):
            if len(kinds) != 1 or kinds[0] not in (INT, FLOAT):
                self.fail(node, f"{name}() takes one number")
            return INT if name == "int" else FLOAT
        if name == "point":
            if kinds:
                self.fail(node, "point() takes no arguments (its length is D)")
            return POINT
        if name == "stack":
            if kinds:
                self.fail(node, f"stack() takes no arguments (its length is {STACK_DEPTH})")
            return STACK
        if name == "range":
            self.fail(node, "range() can only appear in a for loop")
        if name in self.callees:
            return FLOAT
        self.fail(node, f"unknown function {name!r}")


class Kernel:
    """A checked kernel function: its AST, signature and the type of every name it uses.

    Parameters
    ----------
    fn : function, str or ast.FunctionDef
        A Python function in the subset, the source text of one, or its syntax tree (as
        :func:`parse_function` gives it: a scalar plug-in's, rewritten, keeps the lines of the
        user's file).
    callees : iterable of str
        Names of other kernel functions it may call.
    """

    def __init__(self, fn, callees=()):
        self.function = parse_function(fn)
        self.name = self.function.name
        self.signature = Signature(self.function)
        self.types = _Checker(self.function, set(callees)).run()

    def render(self, dialect: str, dim: int, float_name: str = "float64") -> str:
        """Source text in ``dialect`` ("numba", "cuda" or "warp") for dimension ``dim``."""
        return render(self, dialect, dim, float_name)

    def renamed(self, name: str) -> Kernel:
        """The same kernel under another name (its messages keep the author's name)."""
        other = copy.copy(self)
        other.function = copy.deepcopy(self.function)
        other.function.name = other.name = name
        return other

    def same_code(self, other: Kernel) -> bool:
        """Whether ``other`` is this kernel's code, whatever either is named."""
        return self._code == other._code

    @property
    def _code(self) -> str:
        """Its arguments and body, without the name (and without line numbers)."""
        code = self.__dict__.get("_code_text")
        if code is None:
            code = ast.dump(self.function.args) + ast.dump(ast.Module(self.function.body, []))
            self.__dict__["_code_text"] = code
        return code

    def check_indices(self, dim: int) -> None:
        """Refuse constant indices outside the point, a ``point()`` or a ``stack()`` in ``dim`` dimensions.

        Raises
        ------
        KernelError
            Naming the line, for ``p[D]``, ``p[2]`` in 2-D, ``p[-1]`` or ``s[64]`` of a stack.
        """
        point = self.signature.names[0]
        for node in ast.walk(self.function):
            if not (isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name)):
                continue
            name = node.value.id
            kind = self.types.get(name)
            if kind not in (POINT, STACK):
                continue
            index = constant_int(node.slice, dim)
            if index is None:
                continue
            length = dim if kind == POINT else STACK_DEPTH
            what = (f"the point {name!r} has D = {dim} coordinates" if name == point else
                    f"the local point {name!r} has D = {dim} entries" if kind == POINT else
                    f"the stack {name!r} has {STACK_DEPTH} entries")
            if index < 0:
                last = f" (write {name}[D - 1] for the last)" if kind == POINT else ""
                _fail(self.function, node, f"negative index {index}: indices count from 0; {what}, "
                      f"{name}[0] to {name}[{length - 1}]{last}")
            if index >= length:
                _fail(self.function, node, f"index {index} is out of range: {what}, {name}[0] to "
                      f"{name}[{length - 1}]")


#: Functions the Warp dialect calls for Python's ``//`` and ``%`` (Warp's ``%`` follows C, and
#: its float ``//`` is ``floor(a / b)``, which is not Python's ``1.0 // 0.1 == 9.0``). The float
#: ones are CPython's ``float_divmod``; ``F`` is the float type. Ints divided by zero give 0 here
#: (C would stop the program), floats NaN or infinity.
_WARP_HELPERS = {
    "nd_floordiv_i": """@wp.func
def nd_floordiv_i(a: int, b: int):
    if b == 0:
        return 0
    q = a / b
    if a % b != 0 and (a < 0) != (b < 0):
        q = q - 1
    return q
""",
    "nd_mod_i": """@wp.func
def nd_mod_i(a: int, b: int):
    if b == 0:
        return 0
    m = a % b
    if m != 0 and (m < 0) != (b < 0):
        m = m + b
    return m
""",
    "nd_floordiv_f": """@wp.func
def nd_floordiv_f(a: F, b: F):
    m = wp.mod(a, b)
    d = (a - m) / b
    if m != F(0.0):
        if (b < F(0.0)) != (m < F(0.0)):
            d = d - F(1.0)
    if d != F(0.0):
        q = wp.floor(d)
        if d - q > F(0.5):
            q = q + F(1.0)
        return q
    return F(0.0) * (a / b)
""",
    "nd_mod_f": """@wp.func
def nd_mod_f(a: F, b: F):
    m = wp.mod(a, b)
    if m != F(0.0):
        if (b < F(0.0)) != (m < F(0.0)):
            m = m + b
    else:
        m = F(0.0) * b
    return m
""",
}


def warp_prelude(float_name: str, text: str) -> str:
    """The Warp helpers that ``text`` (kernels printed in the Warp dialect) calls, to go before it."""
    used = [re.sub(r"\bF\b", f"wp.{float_name}", source) for name, source in _WARP_HELPERS.items()
            if f"{name}(" in text]
    return "\n\n".join(used) + "\n\n" if used else ""


# -------------------------------------------------------------------- printers
class _Printer(ast.NodeTransformer):
    """Rewrites a checked kernel for one dialect; ``ast.unparse`` then prints it."""

    def __init__(self, dialect: str, dim: int, types: dict[str, str], float_name: str):
        self.dialect = dialect
        self.dim = dim
        self.types = types
        self.float_name = float_name  # "float64" or "float32"

    @staticmethod
    def kind(node) -> str:
        """The type the checker found for an expression of the original function."""
        return node.kind

    @property
    def warp(self) -> bool:
        return self.dialect == "warp"

    def to_float(self, node):
        """``node`` (already printed) cast to the float type where Warp needs it."""
        return ast.Call(ast.Attribute(ast.Name("wp"), self.float_name), [node], [])

    def printed_float(self, original):
        printed = self.visit(original)
        if self.warp and self.kind(original) == INT:
            return self.to_float(printed)
        return printed

    def visit_Name(self, node):
        if node.id == "D":
            return ast.Constant(self.dim)
        return node

    def visit_Constant(self, node):
        if self.warp and isinstance(node.value, float):
            return self.to_float(ast.Constant(node.value))
        return node

    def visit_Attribute(self, node):  # math.pi, math.e
        return self.visit_Constant(ast.Constant(MATH_CONSTANTS[node.attr]))

    def float_operand(self, original):
        """``original`` printed and, if an int, made a float in every dialect (for ``**``)."""
        printed = self.visit(original)
        if self.kind(original) != INT:
            return printed
        return self.to_float(printed) if self.warp else ast.Call(ast.Name("float"), [printed], [])

    def visit_BinOp(self, node):
        if isinstance(node.op, ast.Pow):  # always float ** float, as Python's pow(float, float)
            left, right = self.float_operand(node.left), self.float_operand(node.right)
            if self.warp:
                return ast.Call(ast.Attribute(ast.Name("wp"), "pow"), [left, right], [])
            return ast.BinOp(left, ast.Pow(), right)
        mixed = self.kind(node) == FLOAT
        left = self.printed_float(node.left) if mixed else self.visit(node.left)
        right = self.printed_float(node.right) if mixed else self.visit(node.right)
        if self.warp and isinstance(node.op, (ast.FloorDiv, ast.Mod)):
            # Numba follows Python; Warp's % follows C: call the helpers of warp_prelude.
            helper = ("nd_floordiv_" if isinstance(node.op, ast.FloorDiv) else "nd_mod_") + ("f" if mixed else "i")
            return ast.Call(ast.Name(helper), [left, right], [])
        return ast.BinOp(left, node.op, right)

    def visit_Compare(self, node):
        values = [node.left, *node.comparators]
        mixed = FLOAT in {self.kind(v) for v in values}
        printed = [self.printed_float(v) if mixed else self.visit(v) for v in values]
        if len(node.ops) == 1:
            return ast.Compare(printed[0], node.ops, [printed[1]])
        # Chains become explicit conjunctions (Warp does not chain comparisons).
        parts = [ast.Compare(printed[i], [op], [printed[i + 1]]) for i, op in enumerate(node.ops)]
        return ast.BoolOp(ast.And(), parts)

    def visit_IfExp(self, node):
        mixed = self.kind(node) == FLOAT
        body = self.printed_float(node.body) if mixed else self.visit(node.body)
        orelse = self.printed_float(node.orelse) if mixed else self.visit(node.orelse)
        return ast.IfExp(self.visit(node.test), body, orelse)

    def visit_Call(self, node):
        func = node.func
        if isinstance(func, ast.Attribute):  # math.f
            args = [self.printed_float(a) for a in node.args]
            if self.warp:
                name = "abs" if func.attr == "fabs" else func.attr
                return ast.Call(ast.Attribute(ast.Name("wp"), name), args, [])
            return ast.Call(func, args, [])
        name = func.id
        if name in ("min", "max", "abs"):
            mixed = self.kind(node) == FLOAT
            args = [self.printed_float(a) if mixed else self.visit(a) for a in node.args]
            if not self.warp:
                return ast.Call(func, args, [])
            result = args[0]
            if name == "abs":
                return ast.Call(ast.Attribute(ast.Name("wp"), "abs"), [result], [])
            for arg in args[1:]:  # wp.min/wp.max take two arguments
                result = ast.Call(ast.Attribute(ast.Name("wp"), name), [result, arg], [])
            return result
        if name == "float":
            arg = self.visit(node.args[0])
            return self.to_float(arg) if self.warp else ast.Call(func, [arg], [])
        if name in ("point", "stack"):
            return ast.parse(self.local_array(name), mode="eval").body
        return ast.Call(func, [self.visit(a) for a in node.args], [])

    def local_array(self, kind: str) -> str:
        """The expression making a local ``point()`` (D floats) or ``stack()`` (ints) in this dialect."""
        if self.warp:  # types the generated module defines (ndpack.kernels.compile.warp_module)
            return "VecD()" if kind == "point" else "Stack()"
        length, numba_type, numpy_type = ((self.dim, self.float_name, "np.float64") if kind == "point"
                                          else (STACK_DEPTH, "int32", "np.int64"))
        if self.dialect == "cuda":
            return f"cuda.local.array({length}, {numba_type})"
        return f"np.empty({length}, {numpy_type})"

    def visit_Assign(self, node):
        target = node.targets[0]
        value = self.float_value_for(target, node.value)
        bare = value.operand if isinstance(value, ast.UnaryOp) and isinstance(value.op, ast.USub) else value
        if self.warp and isinstance(bare, ast.Constant) and type(bare.value) is int:
            # Warp treats a name bound to a bare constant as a constant, which a dynamic loop
            # may not change (``n = 0`` then ``n += 1`` in the loop); int(0) makes a variable.
            value = ast.Call(ast.Name("int"), [value], [])
        return ast.Assign([self.visit(target)], value)

    def visit_AugAssign(self, node):
        target = node.target
        if isinstance(node.op, (ast.FloorDiv, ast.Mod, ast.Pow)):
            # x op= e as x = x op e, so that it prints as the operator does (a helper, a cast).
            current = copy.deepcopy(target)
            current.ctx = ast.Load()
            if isinstance(target, ast.Name):
                current.kind = self.types[target.id]
            else:
                current.kind = INT if self.types.get(target.value.id) == STACK else FLOAT
            value = ast.BinOp(current, node.op, node.value)
            value.kind = _arithmetic_kind(node.op, {current.kind, self.kind(node.value)})
            return self.visit_Assign(ast.Assign([target], value))
        if self.warp and isinstance(target, ast.Name) and self.types.get(target.id) == FLOAT:
            value = self.printed_float(node.value)
        else:
            value = self.visit(node.value)
        return ast.AugAssign(self.visit(target), node.op, value)

    def float_value_for(self, target, value):
        if isinstance(target, ast.Subscript):
            wants_float = self.types.get(target.value.id) == POINT
        else:
            wants_float = self.types.get(target.id) == FLOAT
        return self.printed_float(value) if wants_float else self.visit(value)

    def visit_Return(self, node):
        return ast.Return(self.printed_float(node.value))

    def visit_For(self, node):
        node.iter = ast.Call(node.iter.func, [self.visit(a) for a in node.iter.args], [])
        node.body = [self.visit(s) for s in node.body]
        return node


def render(kernel: Kernel, dialect: str, dim: int, float_name: str = "float64") -> str:
    """Source text of a checked kernel in ``dialect`` for dimension ``dim``."""
    if dialect not in ("numba", "cuda", "warp"):
        raise ValueError(f"unknown dialect {dialect!r}")
    kernel.check_indices(dim)
    printed = _Printer(dialect, dim, kernel.types, float_name).visit(copy.deepcopy(kernel.function))
    annotations = {POINT: "Any", ARRAY: f"wp.array(dtype=wp.{float_name})", INT: "int",
                   FLOAT: f"wp.{float_name}"}
    for arg, kind in zip(printed.args.args, kernel.signature.types):
        arg.annotation = ast.parse(annotations[kind], mode="eval").body if dialect == "warp" else None
    if dialect == "warp":
        printed.decorator_list = [ast.parse("wp.func", mode="eval").body]
    ast.fix_missing_locations(printed)
    return ast.unparse(printed)
