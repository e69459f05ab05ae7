"""The format registry: each format module registers a :class:`Format`; files are saved and loaded
through it.

The model is trimesh's exchange registry: :data:`FORMATS` maps a format's name to its record
(writer, reader, suffixes, options) and :data:`SUFFIXES` maps a suffix to the format it means
when ``format=`` is not given. Both start empty and are filled by :func:`register`, called at
import time by the modules that implement the formats (:mod:`ndpack.io` imports them all, in
the order of :func:`names`). :func:`save`, :func:`load` and :func:`check` only look formats up
here, and turn whatever a bad file or a refused option raises into a one-line
:class:`~ndpack.errors.NdpackError`.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..errors import DimensionError, NdpackError
from ..packing import Packing
from .limits import printable


@dataclass(frozen=True)
class Format:
    """One file format: its name, suffixes, the dimensions it holds, what it keeps, its options.

    ``write(packing, path, **options)`` writes a file; ``read(path) -> Packing`` reads one (None
    for a format :func:`load` does not read). ``dims`` is ``"any"``, ``"3"`` or a range such as
    ``"1-3"``; ``suffix_dims`` narrows it for some suffixes (the medial sample in ``.ply``), and
    ``dim_message`` (with ``{dim}``) replaces the generic message for a dimension refused.
    ``any_name``: when ``format=`` names it, the file name needs none of its suffixes.
    """

    name: str
    suffixes: tuple[str, ...]
    dims: str
    keeps: str
    options: dict[str, str]
    write: Callable
    read: Callable | None
    suffix_dims: dict[str, str] = field(default_factory=dict)
    dim_message: str | None = None
    any_name: bool = False

    def dim_range(self, suffix: str) -> range:
        """The dimensions this format holds in a file of ``suffix`` (from ``dims``: ``"any"``,
        ``"3"``, ``"1-3"``)."""
        dims = self.suffix_dims.get(suffix.lower(), self.dims)
        if dims == "any":
            return range(1, 1 << 30)
        low, _, high = dims.partition("-")
        return range(int(low), int(high or low) + 1)


#: Every registered format by name, in the order registered (that of :func:`names`).
FORMATS: dict[str, Format] = {}

#: The format each suffix means when ``format=`` is not given (filled by :func:`register`).
SUFFIXES: dict[str, str] = {}


def register(fmt: Format, default_for: tuple[str, ...] = ()) -> Format:
    """Add ``fmt`` to :data:`FORMATS`, and make it the format of the suffixes ``default_for``
    (some of ``fmt.suffixes``) when no ``format=`` is given; returns ``fmt``.

    A format module calls it once per format at import time, for instance::

        register(Format("ply", (".ply",), "1-3", "spheres, rounds, metadata", {"encoding": "binary|ascii"},
                        write_ply, read_ply), default_for=(".ply",))
    """
    if fmt.name in FORMATS:
        raise ValueError(f"a format named {fmt.name!r} is already registered")
    taken = [suffix for suffix in default_for if suffix in SUFFIXES or suffix not in fmt.suffixes]
    if taken:
        raise ValueError(f"the {fmt.name} format cannot be the default for {', '.join(taken)}")
    FORMATS[fmt.name] = fmt
    for suffix in default_for:
        SUFFIXES[suffix] = fmt.name
    return fmt


# ---------------------------------------------------------------------------------- public API
def save(packing: Packing, path, format: str | None = None, **options) -> Path:
    """Write ``packing`` to ``path`` in the format of its suffix, or the one named; returns the path.

    Parameters
    ----------
    packing : Packing
    path : str or Path
    format : str, optional
        A name from :func:`names`; needed for ``liggghts``, ``medial`` and ``curobo`` in
        ``.json``, whose suffixes (``.json``, ``.data``, ``.ply``, ``.csv``) default to other
        formats.
    **options
        Format options (see :func:`table`): ``encoding`` ("binary" or "ascii") for ply, vtp
        and medial .ply; ``header_type`` ("UInt64" or "UInt32") for vtp; ``subdivisions`` for
        mesh; ``link`` for curobo; ``density`` (a positive number, default 1) for lammps and
        liggghts.
    """
    path = Path(path)
    fmt = check(path, format, packing.dim, **options)
    try:
        fmt.write(packing, path, **options)
    except OSError as error:
        raise NdpackError(f"cannot write {path}: {error.strerror or error}") from error
    return path


def check(path, format: str | None = None, dim: int | None = None, **options) -> Format:
    """The format :func:`save` would write ``path`` in; raises if it would refuse.

    Checks the suffix (or ``format``), the options' names and, given ``dim``, that the format
    holds packings of that dimension, so that a long packing can be refused before it starts
    rather than after it ends.

    Returns
    -------
    Format
    """
    path = Path(path)
    fmt = resolve(path, format, "save to")
    unknown = sorted(set(options) - set(fmt.options))
    if unknown:
        accepted = ", ".join(fmt.options) or "none"
        raise NdpackError(f"the {fmt.name} format has no option {', '.join(unknown)} (its options: {accepted})")
    if dim is not None:
        allowed = fmt.dim_range(path.suffix)
        if dim not in allowed and fmt.dim_message is not None:
            raise DimensionError(fmt.dim_message.format(dim=dim))
        require_dim(dim, allowed, f"the {fmt.name} format ({path.suffix.lower()})")
    return fmt


def load(path, format: str | None = None) -> Packing:
    """Read a packing from any format but ``medial`` (see :func:`~ndpack.io.load_medial`).

    Native files (npz, csv, json) come back as they were saved (every bit of the spheres);
    the others as described in :mod:`ndpack.io`'s table.
    """
    path = existing(path)
    fmt = resolve(path, format, "load")
    if fmt.read is None:
        raise NdpackError(f"the {fmt.name} format is read with ndpack.io.load_{fmt.name}({str(path)!r}), not load()")
    return reading(fmt, path, fmt.read)


def names() -> list[str]:
    """The format names, in the order of :func:`table`."""
    return list(FORMATS)


def table() -> str:
    """The formats as a plain-text table (name, suffixes, dimensions, what is kept, save options)."""
    rows = [("name", "suffixes", "dims", "keeps", "options")]
    for fmt in FORMATS.values():
        options = ", ".join(f"{key}={value}" for key, value in fmt.options.items()) or "-"
        rows.append((fmt.name, " ".join(fmt.suffixes), fmt.dims, fmt.keeps, options))
    widths = [max(len(row[i]) for row in rows) for i in range(4)]
    return "\n".join("  ".join(cell.ljust(width) for cell, width in zip(row, widths)) + "  " + row[4] for row in rows)


# ---------------------------------------------------------------------------------- for the format modules
def existing(path) -> Path:
    """``path`` as a Path, if it names a file; else a one-line error."""
    path = Path(path)
    if not path.exists():
        raise NdpackError(f"no such packing file: {path}")
    if path.is_dir():
        raise NdpackError(f"{path} is a folder, not a packing file")
    return path


def resolve(path: Path, format: str | None, verb: str) -> Format:
    """The format named (checked against the suffix), or the one the suffix means."""
    suffix = path.suffix.lower()
    if format is not None:
        fmt = FORMATS.get(str(format).lower())
        if fmt is None:
            raise NdpackError(f"unknown format {format!r}: use one of {', '.join(FORMATS)}")
        if suffix not in fmt.suffixes and not fmt.any_name:
            raise NdpackError(
                f"cannot {verb} {path.name!r} as {fmt.name}: its file name must end in {' or '.join(fmt.suffixes)}"
            )
        return fmt
    if suffix not in SUFFIXES:
        others = ", ".join(s for s in SUFFIXES if s not in (".npz", ".csv"))
        what = f"unknown suffix {suffix!r}" if suffix else "no suffix"
        raise NdpackError(
            f"cannot {verb} {path.name!r}: {what}; use a .npz or .csv file name (ndpack's own), or {others} "
            f"(format= picks one of {', '.join(FORMATS)})"
        )
    return FORMATS[SUFFIXES[suffix]]


def reading(fmt: Format, path: Path, read: Callable):
    """Run a reader; anything a bad file makes it raise becomes one line naming file and reason."""
    try:
        return read(path)
    except NdpackError:
        raise
    except (KeyError, IndexError, TypeError, ValueError, OSError, EOFError, SyntaxError, zipfile.BadZipFile,
            RecursionError, MemoryError) as error:
        # SyntaxError covers xml.etree's ParseError; ValueError covers JSON and base64 errors. The
        # loaders check sizes and nesting first (ndpack.io.limits): the last two are a backstop.
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        if isinstance(error, RecursionError):
            reason = "it is nested too deep to read"
        elif isinstance(error, MemoryError):
            reason = "reading it needs more memory than is free"
        elif path.is_file() and path.stat().st_size == 0:
            reason = "it is empty (0 bytes)"
        elif isinstance(error, json.JSONDecodeError):
            reason = f"its JSON is not valid ({error.msg}, at character {error.pos})"
        elif isinstance(error, UnicodeDecodeError):
            reason = "it is binary, not text"
        elif isinstance(error, KeyError):
            key = str(error.args[0]) if error.args else reason
            reason = f"it has no {key.removesuffix(' is not a file in the archive')!r}"
        elif "Object arrays" in reason:  # numpy's advice to allow pickles: ndpack never loads them
            reason = "it holds arrays of Python objects (pickled), which ndpack never loads"
        elif "pickle" in reason:
            reason = "it is not an archive of arrays (NumPy would read it as pickled objects, which ndpack never loads)"
        raise NdpackError(f"{path} is not a readable ndpack packing ({fmt.name} format): {printable(reason)}") \
            from error


def require_dim(dim: int, allowed: range, what: str) -> None:
    """Refuse a ``dim``-D packing that ``what`` cannot hold, with a one-line DimensionError."""
    if dim not in allowed:
        if allowed.stop - allowed.start == 1:
            need = f"{allowed.start}-D spheres"
        else:
            need = f"spheres in {allowed.start} to {allowed.stop - 1} dimensions"
        raise DimensionError(
            f"{what} holds {need}, not a {dim}-D packing: use .npz, .csv or .json, which keep any dimension"
        )


def binary_encoding(encoding: str | None) -> bool:
    """The ``encoding`` option (ply, vtp, medial .ply): True for binary (the default), False for ASCII."""
    if encoding is None or str(encoding).lower() == "binary":
        return True
    if str(encoding).lower() == "ascii":
        return False
    raise NdpackError(f"encoding must be 'binary' or 'ascii', got {encoding!r}")
