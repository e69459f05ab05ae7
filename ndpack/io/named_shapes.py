"""Named shapes for the command line and quick experiments: ``box:dim=4``, ``demo``.

A spec is ``name`` or ``name:key=value,key=value``; every shape takes ``dim`` where it makes
sense. :func:`from_spec` turns a spec into an oracle and explains any mistake.

Third-party packages add named shapes through the entry-point group ``ndpack.shapes``: each
entry is a factory ``f(**numbers) -> Oracle``. In the package's ``pyproject.toml``::

    [project.entry-points."ndpack.shapes"]
    gyroid = "my_shapes:gyroid"      # then: ndpack pack gyroid:dim=5
"""

from __future__ import annotations

import numpy as np

from ..errors import ShapeError
from ..oracle import Oracle
from ..shapes import Ball, Box, Cylinder, Polygon, RoundedBox, Simplex, Torus
from . import limits


def _demo(dim=3):
    """A 3-D machined part: rounded block minus a bore and a spherical pocket."""
    if dim != 3:
        raise ShapeError("the demo part is 3-D only; drop dim= or pick another shape")
    block = RoundedBox([-1.0, -0.6, -0.4], [1.0, 0.6, 0.4], 0.15)
    bore = Cylinder([0.45, 0.0, -1.0], [0.45, 0.0, 1.0], 0.25)
    pocket = Ball([-0.5, 0.0, 0.45], 0.35)
    return block - bore - pocket


def _annulus(dim=2, inner=0.5):
    """A 2-D ring (a 256-gon with a hole) or, in any dimension, a ball minus a ball."""
    if dim == 2:
        outer = Polygon.regular(256, 1.0)
        hole = Polygon.regular(256, float(inner)).outer[::-1]
        return Polygon(outer.outer, holes=[hole])
    return Ball(np.zeros(dim), 1.0) - Ball(np.zeros(dim), float(inner))


def _simplex(dim=3):
    vertices = np.vstack([np.zeros(dim), np.eye(dim)])
    return Simplex(vertices)


BUILTIN = {
    "demo": _demo,
    "box": lambda dim=3: Box(np.zeros(dim), np.ones(dim)),
    "cube": lambda dim=3: Box(np.zeros(dim), np.ones(dim)),
    "square": lambda dim=2: Box(np.zeros(dim), np.ones(dim)),
    "ball": lambda dim=3: Ball(np.zeros(dim), 1.0),
    "simplex": _simplex,
    "torus": lambda dim=3, major=1.0, minor=0.35: Torus([0, 0, 0], float(major), float(minor)),
    "annulus": _annulus,
}


ENTRY_POINT_GROUP = "ndpack.shapes"


def registered() -> dict:
    """Every named shape: the built-in ones, then those of installed packages (``ndpack.shapes``).

    Returns
    -------
    dict
        Name -> factory. A package cannot replace a built-in name.
    """
    from importlib.metadata import entry_points

    shapes = {}
    for entry in entry_points(group=ENTRY_POINT_GROUP):
        shapes.setdefault(entry.name.lower(), entry)
    shapes.update(BUILTIN)
    return shapes


def _parameters(factory) -> dict | None:
    """The keyword parameters a shape factory takes -> their defaults (None where required);
    None if it takes any keyword or its signature cannot be read."""
    import inspect

    try:
        parameters = list(inspect.signature(factory).parameters.values())
    except (TypeError, ValueError):
        return None
    if any(p.kind is p.VAR_KEYWORD for p in parameters):
        return None
    return {p.name: None if p.default is p.empty else p.default for p in parameters
            if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}


def from_spec(spec: str):
    """Build a named shape from ``name[:key=value,...]``, e.g. ``box:dim=4``."""
    shapes = registered()
    name = spec.partition(":")[0].strip().lower()
    if name not in shapes:
        raise ShapeError(f"unknown shape {name!r}; known shapes are: {', '.join(shapes)}")
    keywords = _arguments(spec)[1]
    factory = shapes[name]
    if hasattr(factory, "load"):  # an entry point: import the package only now
        try:
            factory = factory.load()
        except Exception as error:  # noqa: BLE001 - any import failure in a third-party package
            raise ShapeError(f"the package providing shape {name!r} failed to load: {error}") from None
    accepted = _parameters(factory)
    unknown = [key for key in keywords if accepted is not None and key not in accepted]
    if unknown:
        takes = ", ".join(f"{key}={default}" if default is not None else key for key, default in accepted.items())
        raise ShapeError(f"shape {name!r} does not take {', '.join(unknown)}; it takes {takes or 'no parameters'}"
                         + (f" (e.g. {name}:{next(iter(accepted))}=...)" if accepted else ""))
    try:
        shape = factory(**keywords)
    except TypeError as error:
        raise ShapeError(f"shape {name!r} refused {', '.join(keywords)}: {error}") from None
    if not isinstance(shape, Oracle):
        raise ShapeError(f"shape {name!r} came back as {type(shape).__name__}, not an ndpack shape")
    return shape


def spec_dim(spec: str) -> int | None:
    """The dimension of the shape a spec names, read from the spec alone (its ``dim=``, else the
    built-in shape's default), so that it can be compared with a packing's before anything is
    built; None where the spec does not say (a package's shape without ``dim=``)."""
    name, keywords = _arguments(spec)
    if "dim" in keywords:
        return keywords["dim"] if isinstance(keywords["dim"], int) else None
    if name not in BUILTIN:
        return None
    default = (_parameters(BUILTIN[name]) or {}).get("dim")
    return default if isinstance(default, int) else None


def _arguments(spec: str) -> tuple[str, dict]:
    """The name (lower case) and the numbers of ``name[:key=value,...]``; ``dim`` an int from 1 to
    :data:`~ndpack.io.limits.MAX_DIM`, checked before any shape is sized by it."""
    name, _, arguments = spec.partition(":")
    keywords = {}
    for item in filter(None, (part.strip() for part in arguments.split(","))):
        key, equals, value = item.partition("=")
        if not equals:
            raise ShapeError(f"cannot read {item!r} in {spec!r}: write key=value, e.g. box:dim=4")
        try:
            number = float(value)
        except ValueError:
            raise ShapeError(f"{key} must be a number in {spec!r}, got {value!r}") from None
        keywords[key.strip()] = int(number) if number.is_integer() and key.strip() == "dim" else number
    if "dim" in keywords and not 1 <= keywords["dim"] <= limits.MAX_DIM:
        raise ShapeError(f"dim must be a positive integer of at most {limits.MAX_DIM} in {spec!r}")
    return name.strip().lower(), keywords
