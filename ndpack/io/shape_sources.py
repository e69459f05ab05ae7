"""Where a shape comes from, as the command line names it: one string, four kinds.

=============================== ===========================================================
``box:dim=4``, ``demo``         a named shape (:mod:`ndpack.io.named_shapes`, or a package's entry point)
``part.stl``, ``cow.obj``       a triangle mesh file (anything trimesh reads)
``part.py``                     a Python script that sets ``shape`` (an ndpack shape, or a
                                manifold3d, trimesh or shapely object), or defines ``shape()``
``my_shapes:gyroid``            a plug-in: ``module:function`` (or ``module:attribute``),
                                imported from the current folder or the installed packages
=============================== ===========================================================

:func:`load_shape` turns the string into an oracle and explains any mistake in one line. A
packing made from a source records it (``params["source"]``), so ``ndpack verify`` and
``ndpack render`` can rebuild the shape later, but only where it is data (a mesh file or a
built-in spec): a packing file may come from anyone, and :func:`code_in` says which recorded
sources would run code (a script, a module, an installed package's plug-in).
"""

from __future__ import annotations

import importlib
import os
import runpy
import sys
from pathlib import Path

from ..errors import DimensionError, ShapeError
from ..oracle import Oracle
from ..samples import SAMPLES
from ..shapes.adapters import as_oracle
from ..shapes.mesh import TriangleMesh
from .limits import printable
from .named_shapes import BUILTIN, from_spec, registered, spec_dim

#: Suffixes read as triangle meshes (trimesh reads these and more).
MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf", ".3mf", ".dae")


def load_shape(source: str, holes: str | None = None, sign: str | None = None, dim: int | None = None):
    """The shape a source string names; see the module's table.

    Parameters
    ----------
    source : str
    holes : {"cap", "refuse"}, optional
        For a mesh file: what to do with an open mesh (:class:`~ndpack.TriangleMesh`); refused
        for other sources, whose code builds the shape.
    sign : {"auto", "pseudonormal", "winding"}, optional
        For a mesh file: how inside is told (:class:`~ndpack.TriangleMesh`); refused for other
        sources.
    dim : int, optional
        The dimension the shape must have (a packing's): compared with what the source says
        (:func:`source_dim`) before the shape is built, so that a file recording
        ``box:dim=1000000000`` for a 2-D packing costs nothing, and with the shape built.

    Returns
    -------
    Oracle
    """
    text = source.strip()
    shown = printable(text)
    if not text:
        raise ShapeError("the shape is empty: name a built-in shape (e.g. box:dim=3), a mesh file or a script")
    kind = _kind(text)
    if holes is not None and kind != "mesh":
        raise ShapeError(f"--holes applies to a mesh file, and {shown} is not one: leave it out "
                         "(a script passes holes= to ndpack.TriangleMesh itself)")
    if sign is not None and kind != "mesh":
        raise ShapeError(f"--sign applies to a mesh file, and {shown} is not one: leave it out "
                         "(a script passes sign= to ndpack.TriangleMesh itself)")
    if dim is not None:
        _check_dim(source_dim(text), dim, shown)
    path = Path(text).expanduser()
    if path.is_dir():
        raise ShapeError(f"{shown} is a folder, not a mesh file or a script")
    if kind in ("script", "mesh") and not path.exists():
        raise ShapeError(f"no such file: {shown}" + _sample_hint(path))
    if kind == "script":
        shape = _checked(as_oracle(_from_script(path)), shown)
    elif kind == "mesh":
        shape = TriangleMesh.load(path, sign=sign or "auto", holes=holes)
    elif kind == "spec":
        shape = from_spec(text)
    else:
        name, _, attribute = text.partition(":")
        shape = _checked(as_oracle(_from_plugin(name.strip(), attribute.strip())), shown)
    if dim is not None:
        _check_dim(shape.dim, dim, shown)
    return shape


def source_dim(source: str) -> int | None:
    """The dimension of the shape ``source`` names, told without building it: a spec's ``dim=``
    (or a built-in shape's default), 3 for a mesh file; None where only running code would tell
    (a script, a module, a package's shape without ``dim=``)."""
    text = source.strip()
    kind = _kind(text)
    if kind == "mesh":
        return 3
    return spec_dim(text) if kind == "spec" else None


def _check_dim(found: int | None, dim: int, shown: str) -> None:
    if found is not None and found != dim:
        raise DimensionError(f"the shape {shown} is {found}-D, but the packing is {dim}-D: name a {dim}-D shape")


def _kind(text: str) -> str:
    """How :func:`load_shape` reads a stripped source: ``"script"``, ``"mesh"`` (any other
    file), ``"spec"`` (a named shape) or ``"plugin"`` (``module:attribute``)."""
    path = Path(text).expanduser()
    if path.suffix.lower() == ".py":
        return "script"
    if path.suffix.lower() in MESH_SUFFIXES or path.is_file() or "/" in text or os.sep in text:
        return "mesh"
    name, colon, rest = text.partition(":")
    if name.strip().lower() in registered() or not colon or "=" in rest:
        return "spec"
    return "plugin"


def _from_script(path: Path):
    """Run a script and take its ``shape`` (a value, or a function called with no arguments)."""
    folder = str(path.resolve().parent)
    sys.path.insert(0, folder)  # the script may import its neighbours
    try:
        namespace = runpy.run_path(str(path), run_name="__ndpack_shape__")
    except SystemExit as error:
        raise ShapeError(f"{path} exited ({error.code}) instead of defining shape") from None
    except Exception as error:  # noqa: BLE001 - any failure in the user's script, reported in one line
        raise ShapeError(f"{path} failed: {type(error).__name__}: {error}") from None
    finally:
        if sys.path and sys.path[0] == folder:
            sys.path.pop(0)
    if "shape" not in namespace:
        raise ShapeError(
            f"{path} does not set `shape`: end it with, e.g., shape = part (an ndpack or manifold3d solid)"
        )
    return _called(namespace["shape"], f"{path}: shape()")


def _from_plugin(module_name: str, attribute: str):
    if not module_name.replace(".", "").replace("_", "").isalnum() or not attribute.isidentifier():
        raise ShapeError(f"cannot read {module_name}:{attribute}: write module:function, e.g. my_shapes:gyroid")
    if os.getcwd() not in sys.path and "" not in sys.path:
        sys.path.insert(0, os.getcwd())  # as `python -c` would: a module beside the user
    try:
        module = importlib.import_module(module_name)
    except ImportError as error:
        raise ShapeError(
            f"unknown shape {module_name!r}, and no module {module_name!r} to import ({error}); "
            f"see `ndpack pack --help` for the shapes you can name"
        ) from None
    except Exception as error:  # noqa: BLE001 - the plug-in's own import failed
        raise ShapeError(f"importing {module_name} failed: {type(error).__name__}: {error}") from None
    if not hasattr(module, attribute):
        raise ShapeError(f"module {module_name} has no {attribute!r}")
    return _called(getattr(module, attribute), f"{module_name}:{attribute}()")


def _called(value, label: str):
    """A function is called with no arguments; anything else is the shape itself."""
    if callable(value) and not isinstance(value, Oracle) and isinstance(value, type(_called)):
        try:
            return value()
        except Exception as error:  # noqa: BLE001 - the user's function, reported in one line
            raise ShapeError(f"{label} failed: {type(error).__name__}: {error}") from None
    return value


def _checked(shape, source: str):
    if not isinstance(shape, Oracle):
        raise ShapeError(
            f"{source} gave a {type(shape).__name__}, not a shape: return an ndpack shape, or a manifold3d, "
            f"trimesh or shapely solid"
        )
    return shape


def is_mesh_file(source: str) -> bool:
    """Whether :func:`load_shape` reads ``source`` as a triangle mesh file (the one kind that
    takes ``holes``)."""
    return _kind(source.strip()) == "mesh"


def code_in(source: str) -> str | None:
    """What code :func:`load_shape` would run for ``source``, in words, or None where it only
    reads data (a mesh file, a built-in shape spec): the same reading (:func:`_kind`), without
    touching the file system beyond ``is_file``."""
    text = source.strip()
    kind = _kind(text)
    name = text.partition(":")[0].strip()
    if kind == "script":
        return f"the Python script {printable(text)}"
    if kind == "mesh" or (kind == "spec" and name.lower() in BUILTIN):
        return None  # trimesh reads a mesh file as data; a built-in shape is ndpack's own
    if kind == "spec":
        return f"the shape plug-in of an installed package ({name!r})"
    return f"the module {name!r}"


def describe(source: str) -> str:
    """The source as a packing records it: files as absolute paths, so it works from anywhere."""
    path = Path(source.strip()).expanduser()
    if path.is_file():
        return str(path.resolve())
    return source.strip()


def _sample_hint(path: Path) -> str:
    """For a missing file named like a sample mesh (``cow.obj``): how to get it."""
    if path.stem in SAMPLES:
        return f" (the docs' sample meshes: `ndpack samples` writes {path.stem}.obj and the others here)"
    return ""
