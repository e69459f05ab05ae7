"""Scalar plug-ins: a distance written once, for one point, that runs on every backend.

Example (a 5-D "gyroid-like" shell, see ``examples/gyroid_5d.py``)::

    import math
    import ndpack as nd

    @nd.scalar_plugin(dim=5, bounds=[[-1] * 5, [1] * 5], params=[3.0, 0.3])
    def gyroid(p, params):
        s = 0.0
        for i in range(D):                      # D is the dimension
            s += math.sin(params[0] * p[i]) * math.cos(params[0] * p[(i + 1) % D])
        return (abs(s) / params[0] - params[1]) / math.sqrt(D)   # scaled to stay 1-Lipschitz

The function takes the point ``p`` and the parameter array ``params`` and is written in the
kernel language (:mod:`ndpack.kernels.language`): arithmetic, ``math`` functions, indexing, loops,
``if``, ``min``/``max``/``abs``. ndpack prints it for Numba (CPU and CUDA) and Warp; the NumPy
backend and :meth:`~ndpack.Oracle.distance` run its Numba CPU form over all points.
"""

from __future__ import annotations

import ast
from typing import Callable

import numpy as np

from ..errors import BoundsError, KernelError, OracleError
from ..kernels.compile import numba_evaluator
from ..kernels.compiled import compiled_program
from ..kernels.language import Kernel, constant_int, located_error, parse_function
from .plugin import Function


def _with_offset(fn, prefix="user_"):
    """``fn(p, params)`` as the syntax tree of a library-style kernel ``user_fn(p, prm, o: int)``.

    Every ``params[e]`` becomes ``prm[o + e]``, so the user's parameters can sit anywhere in a
    program's flat parameter array. The tree keeps the line numbers of the user's file and the
    function's own name for messages (:func:`~ndpack.kernels.language.parse_function`).

    Returns
    -------
    function : ast.FunctionDef
    params : list of (ast.Subscript, ast.expr)
        Every ``params[e]`` (rewritten) with its index ``e`` as the user wrote it.
    """
    function = parse_function(fn)
    args = function.args.args
    if len(args) != 2 or function.args.vararg or function.args.kwarg or function.args.kwonlyargs:
        raise KernelError(
            f"a scalar plug-in takes exactly two arguments, (p, params): the point and its "
            f"parameters; {function.name!r} takes {len(args)}"
        )
    params_name = args[1].arg
    point_name = args[0].arg
    indexed = []

    class Rewrite(ast.NodeTransformer):
        def visit_Subscript(self, node):
            if isinstance(node.value, ast.Name) and node.value.id == params_name:
                index = self.visit(node.slice)
                node.value = ast.Name("prm", ast.Load())
                node.slice = ast.BinOp(ast.Name("o", ast.Load()), ast.Add(), index)
                indexed.append((node, index))
                return node
            self.generic_visit(node)
            return node

        def visit_Name(self, node):
            if node.id in ("prm", "o") and node.id not in (params_name, point_name):
                raise located_error(function, node, "the names 'prm' and 'o' are reserved in plug-ins")
            if node.id == params_name:
                raise located_error(function, node, "use the parameters only by index, params[i]")
            return node

    function = Rewrite().visit(function)
    function.name = prefix + function.name
    function.args.args = [ast.arg(point_name), ast.arg("prm"), ast.arg("o", ast.Name("int", ast.Load()))]
    ast.fix_missing_locations(function)
    return function, indexed


def _check_params(function, indexed, dim: int, count: int) -> None:
    """Refuse a constant ``params[e]`` outside the ``count`` parameters (``e`` may use ``D``)."""
    for node, index in indexed:
        value = constant_int(index, dim)
        if value is None or 0 <= value < count:
            continue
        have = (f"there are {count} params, params[0] to params[{count - 1}]" if count > 1 else
                "there is 1 param, params[0]" if count else "there are no params (pass them as params=[...])")
        raise located_error(function, node, f"params[{value}] is out of range: {have}")


class ScalarFunction(Function):
    """A user's scalar distance function ``fn(p, params) -> float``, used as a shape on every backend.

    Parameters
    ----------
    fn : function
        Written in the kernel language (see this module); it must be defined with ``def`` in a
        file or notebook cell, so that its source can be read.
    dim : int
        Dimension, at least 1; ``D`` inside ``fn``.
    bounds : (2, dim) array_like
        A finite box enclosing the shape.
    params : sequence of float
        The values ``fn`` reads as ``params[i]``.
    exact_inside, exact_outside, name :
        As for :class:`~ndpack.Function`.

    Raises
    ------
    KernelError
        If ``fn`` uses something outside the kernel language, or a constant index outside
        ``p`` (``0 .. dim - 1``) or ``params``; the message names the line of ``fn``'s file.

    Notes
    -----
    Several instances of one function (other ``params``) share one compiled kernel, also in
    one CSG tree; each reads its own parameters.
    """

    numpy_only = False

    def __init__(self, fn, dim, bounds, params=(), exact_inside=False, exact_outside=False, name=None):
        if not callable(fn):
            raise TypeError(f"fn must be a function (p, params) -> float, got {type(fn).__name__}")
        try:
            values = np.asarray(params, dtype=np.float64).ravel()
        except (TypeError, ValueError):
            raise OracleError(f"params must be a sequence of numbers, got {params!r}") from None
        if not np.all(np.isfinite(values)):
            raise OracleError(f"params must be finite, got {values.tolist()}")
        self.params = values
        function, indexed = _with_offset(fn)
        self.kernel = Kernel(function)
        self.scalar_fn = fn
        super().__init__(
            self._evaluate, dim, bounds, exact_inside=exact_inside, exact_outside=exact_outside,
            name=name or fn.__name__,
        )
        self.kernel.check_indices(self.dim)
        _check_params(self.kernel.function, indexed, self.dim, values.size)
        self.__doc__ = fn.__doc__ or type(self).__doc__

    def _evaluate(self, points):
        """(n,) distances at (n, dim) points, by the Numba CPU form of the kernel."""
        flat = compiled_program(self)
        evaluate = self.__dict__.get("_evaluator")
        if evaluate is None:
            evaluate = self.__dict__["_evaluator"] = numba_evaluator(flat.program)
        return evaluate(points, flat.params)

    def _tape(self, tape):
        tape.user(self.kernel, self.params)

    def _kernel(self, program):
        offset = program.add_params(self.params)
        name = program.add_kernel(self.kernel)
        return program.define(f"def _(p, prm):\n    return {name}(p, prm, {offset})\n")

    def __repr__(self):
        return f"ScalarFunction({self.name!r}, dim={self.dim})"


def scalar_plugin(dim: int, bounds=None, params=(), **flags) -> Callable[[Callable], ScalarFunction]:
    """Decorator that turns a scalar distance function into a :class:`ScalarFunction`.

    Examples
    --------
    >>> @scalar_plugin(dim=2, bounds=[[-1, -1], [1, 1]], params=[1.0])
    ... def disc(p, params):
    ...     return math.sqrt(p[0] * p[0] + p[1] * p[1]) - params[0]
    """
    if callable(dim):
        raise TypeError("scalar_plugin needs its arguments: @ndpack.scalar_plugin(dim=..., bounds=...)")
    if bounds is None:
        raise BoundsError(f"scalar_plugin needs bounds: a (2, {dim}) box [lower corner, upper corner]")

    def wrap(fn) -> ScalarFunction:
        return ScalarFunction(fn, dim, bounds, params=params, **flags)

    return wrap
