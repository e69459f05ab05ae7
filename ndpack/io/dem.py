"""Sphere files that discrete-element (DEM) codes read directly: LAMMPS, LIGGGHTS and Yade (2-3-D).

LAMMPS data file (``lammps``, ``.data``)
    Read by LAMMPS's ``read_data`` with ``atom_style sphere``. A header (the first line is a
    title that LAMMPS skips; ``N atoms``, ``1 atom types``, the box lines ``xlo xhi``, ``ylo
    yhi``, ``zlo zhi``), then an ``Atoms # sphere`` section of one row a sphere::

        atom-ID atom-type diameter density x y z

    IDs run from 1 in the packing's order. Atom types are size classes (option ``types``): by
    default one a class of the packing's discrete size distribution (its radii times the bed's
    ``scale``, each sphere the class nearest its radius), else one a distinct radius where there
    are at most ``MAX_TYPES`` of them, else 1 for all; ``types=one`` gives every sphere type 1. A
    header comment lists each type's radius. No ``Masses`` section: atom_style sphere sets each
    particle's mass from its density and diameter, and LAMMPS refuses per-type masses for it (the
    ``mass`` command's documentation). ``density`` is mass per
    volume: LAMMPS sets each mass to ``density * 4/3 pi r**3``, the volume of a 3-D ball, in 2-D
    simulations too (``set density/disc`` makes them discs of mass ``density * pi r**2``). A 2-D
    packing is written with z = 0, a z box that straddles 0, and a header comment to use
    ``dimension 2`` (LAMMPS also needs z periodic in 2-D).

LIGGGHTS data file (``liggghts``)
    LIGGGHTS's ``read_data`` reads the same rows for ``atom_style granular`` (or ``sphere``), so
    the file is the same but for its title and comments, and its section line ``Atoms``
    without the style comment that older LAMMPS versions, LIGGGHTS among them, do not strip
    there. In 2-D, LIGGGHTS takes ``density`` as mass per area (a disc: ``density * pi r**2``);
    in 3-D as mass per volume.

Yade text file (``yade``, ``.txt``)
    What ``yade.ymport.text`` reads and ``yade.export.text`` writes: a first line
    ``#format x_y_z_r``, then ``x y z r`` a sphere. 3-D only. Yade takes no blank lines (its
    reader fails on them), so none are written. A periodic packing's cell goes in a comment line
    that Yade skips, as the input script's lines that set it (``O.periodic = True``,
    ``O.cell.setBox(Lx, Ly, Lz)``, with the cell's lower corner), and is read back.

Numbers are written with 17 significant digits (``%.17g``), so every centre and radius reads
back to the same float64 (a diameter ``2 r`` is exact in binary floating point).

The array functions (:func:`data_box`, :func:`write_data`, :func:`read_data`, :func:`write_yade`,
:func:`read_yade`) take and return NumPy arrays; the formats registered here wrap them for
packings, with the box from the packing's recorded bounds and periods, else its shape's bounds,
else the spheres' extent. Loaded back, a data file whose header comment holds the input script's
``boundary p p p`` line (as ndpack writes it) records its box and periods again
(``params["bounds"]``, ``params["period"]``), as does a Yade file's cell comment.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from ..errors import DimensionError, NdpackError
from ..packing import Packing
from .metadata import packing_from
from .registry import Format, register, require_dim

#: The columns of an ``atom_style sphere`` row.
SPHERE_COLUMNS = ("atom-ID", "atom-type", "diameter", "density", "x", "y", "z")

#: Distinct radii up to which each gets an atom type of its own (more: one type for all, as a
#: continuous distribution's spheres each differ).
MAX_TYPES = 32

#: LAMMPS reads lines up to 254 characters; ndpack's comment lines stay well inside.
_TITLE_LIMIT = 200

_DIMENSION_2 = re.compile(r"\bdimension\s+2\b", re.IGNORECASE)
#: The input script's ``boundary`` line, as ndpack writes it in a header comment: p, f, s, m or two of them an axis.
_BOUNDARY = re.compile(r"\bboundary\s+([pfsm]{1,2})\s+([pfsm]{1,2})\s+([pfsm]{1,2})\b")
_AXES = "xyz"


# ---------------------------------------------------------------------------------- the box
def density_value(density) -> float:
    """``density`` as a positive finite float; numbers given as text (``"2500"``) are accepted."""
    if isinstance(density, bool):
        raise NdpackError(f"density must be a positive number, got {density!r}")
    try:
        value = float(density)
    except (TypeError, ValueError):
        raise NdpackError(f"density must be a positive number, got {density!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise NdpackError(f"density must be a positive number, got {density!r}")
    return value


def data_box(centers, radii, bounds=None, periods=None) -> tuple[np.ndarray, np.ndarray]:
    """The simulation box of a LAMMPS data file for these spheres.

    Parameters
    ----------
    centers : (n, d) float64
        ``d`` is 2 or 3.
    radii : (n,) float64
    bounds : (2, d) array_like, optional
        Lower and upper corners of the domain (a shape's bounds, or a periodic cell's). Without
        them the box is the spheres' extent: ``min(c - r)`` to ``max(c + r)`` on each axis
        (``-0.5`` to ``0.5`` for no spheres).
    periods : sequence of d (float or None), optional
        The period of each axis, None for an axis that is not periodic. A periodic axis runs
        from its lower bound to that bound plus its period.

    Returns
    -------
    box : (2, 3) float64
        ``[[xlo, ylo, zlo], [xhi, yhi, zhi]]``. In 2-D, z runs from ``-dmax / 2`` to
        ``dmax / 2`` (``dmax`` the largest diameter, 1 for no spheres): it straddles 0, as LAMMPS
        requires of a 2-D box.
    periodic : (3,) bool
        Which axes have a period (z is False in 2-D: the data file does not say; LAMMPS's input
        script makes z periodic for ``dimension 2``).
    """
    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    dim = _check_spheres(centers, radii)
    if bounds is None:
        if len(radii):
            lower = (centers - radii[:, None]).min(axis=0)
            upper = (centers + radii[:, None]).max(axis=0)
        else:
            lower, upper = np.full(dim, -0.5), np.full(dim, 0.5)
    else:
        try:
            corners = np.asarray(bounds, dtype=np.float64)
        except (TypeError, ValueError):
            raise NdpackError(f"the bounds must be a (2, {dim}) array of numbers, got {bounds!r}") from None
        if corners.shape != (2, dim) or not np.isfinite(corners).all() or not (corners[0] < corners[1]).all():
            raise NdpackError(f"the bounds must be a (2, {dim}) array of finite numbers, lower below upper, "
                              f"got {corners.tolist()}")
        lower, upper = corners[0].copy(), corners[1].copy()
    periodic = np.zeros(3, dtype=bool)
    if periods is not None:
        periods = list(periods)
        if len(periods) != dim:
            raise NdpackError(f"the periods must be a list of {dim} numbers or None, got {periods!r}")
        for axis, period in enumerate(periods):
            if period is None:
                continue
            try:
                length = float(period)
            except (TypeError, ValueError):
                length = float("nan")
            if isinstance(period, bool) or not (math.isfinite(length) and length > 0):
                raise NdpackError(f"the period of axis {axis} must be a positive number or None, got {period!r}")
            upper[axis] = lower[axis] + length
            periodic[axis] = True
    box = np.zeros((2, 3))
    box[:, :dim] = [lower, upper]
    if dim == 2:
        half = float(radii.max()) if len(radii) else 0.5
        box[:, 2] = [-half, half]
    return box, periodic


def size_types(radii, classes=None) -> tuple[np.ndarray, np.ndarray]:
    """Atom types by size: each sphere's type (n,) int64, from 1, and each type's radius (k,).

    With ``classes`` (k,), a discrete distribution's radii, each sphere takes the class nearest
    its radius (in log); else each distinct radius is a type where there are at most
    ``MAX_TYPES``, else every sphere is type 1 (its radius: the largest).
    """
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    if classes is not None:
        classes = np.sort(np.asarray(classes, dtype=np.float64).reshape(-1))
        if len(radii) == 0:
            return np.zeros(0, dtype=np.int64), classes
        nearest = np.abs(np.log(radii)[:, None] - np.log(classes)[None]).argmin(axis=1)
        return nearest.astype(np.int64) + 1, classes
    distinct = np.unique(radii)
    if 0 < len(distinct) <= MAX_TYPES:
        return np.searchsorted(distinct, radii).astype(np.int64) + 1, distinct
    return np.ones(len(radii), dtype=np.int64), distinct[-1:] if len(distinct) else np.zeros(0)


# ---------------------------------------------------------------------------------- LAMMPS, LIGGGHTS
def write_data(path, centers, radii, box, periodic=(False, False, False), density=1.0, program: str = "LAMMPS",
               notes=(), types=None, type_radii=None) -> None:
    """Write spheres as a data file for ``read_data`` with ``atom_style sphere``.

    Parameters
    ----------
    path : str or Path
    centers : (n, d) float64
        ``d`` is 2 (written with z = 0) or 3.
    radii : (n,) float64
        Written as diameters ``2 r``.
    box : (2, 3) float64
        ``[[xlo, ylo, zlo], [xhi, yhi, zhi]]`` (see :func:`data_box`).
    periodic : (3,) bool
        Axes with a period; only the header's ``boundary`` hint uses them.
    density : float or str
        Every sphere's density. LAMMPS: mass per volume, ``mass = density * 4/3 pi r**3`` in 2-D
        as well. LIGGGHTS: the same in 3-D, mass per area (``density * pi r**2``) in 2-D.
    program : "LAMMPS" or "LIGGGHTS"
        The title and comments; LIGGGHTS also gets a bare ``Atoms`` section line.
    notes : sequence of str
        More header comment lines (where the box came from, say).
    types : (n,) int, optional
        Each sphere's atom type, from 1 (:func:`size_types`); default 1 for all.
    type_radii : (k,) float64, optional
        Each type's radius, for the header comment that says which is which.
    """
    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    dim = _check_spheres(centers, radii)
    if dim not in (2, 3):
        raise DimensionError(f"a {program} data file holds 2-D or 3-D spheres, not a {dim}-D packing")
    if program not in ("LAMMPS", "LIGGGHTS"):
        raise NdpackError(f"program must be 'LAMMPS' or 'LIGGGHTS', got {program!r}")
    rho = density_value(density)
    box = np.asarray(box, dtype=np.float64)
    if box.shape != (2, 3) or not np.isfinite(box).all() or not (box[0] < box[1]).all():
        raise NdpackError(f"the box must be [[xlo, ylo, zlo], [xhi, yhi, zhi]] with lo < hi, got {box.tolist()}")
    periodic = np.asarray(periodic, dtype=bool).reshape(3)
    count = len(radii)
    types = np.ones(count, dtype=np.int64) if types is None else np.asarray(types, dtype=np.int64).reshape(-1)
    if len(types) != count or (count and types.min() < 1):
        raise NdpackError(f"types must be {count} atom types from 1, got {len(types)} of them")
    type_count = int(types.max()) if count else 1
    style = "granular (or sphere)" if program == "LIGGGHTS" else "sphere"
    title = f"{program} data file for atom_style {style}, written by ndpack: {count} spheres in {dim}-D"
    lines = [title]
    if type_count == 1:
        lines.append("# columns: " + " ".join(SPHERE_COLUMNS) + "; every sphere has type 1")
    else:
        lines.append("# columns: " + " ".join(SPHERE_COLUMNS) + f"; {type_count} atom types, by size")
        if type_radii is not None and len(type_radii) == type_count:
            described = ", ".join(f"{k + 1} r={radius:.6g}" for k, radius in enumerate(type_radii))
            lines.append(("# atom types by radius: " + described)[:_TITLE_LIMIT])
    lines.append("# " + _density_note(program, dim, rho))
    if dim == 2:
        lines.append("# dimension 2: a 2-D packing in x and y, z = 0; put `dimension 2` in the input script")
    lines.append("# " + _boundary_note(program, dim, periodic))
    # One line each, within the line length LAMMPS reads (older versions split a longer line in two).
    lines.extend(("# " + " ".join(str(note).split()))[:_TITLE_LIMIT] for note in notes)
    lines += ["", f"{count} atoms", f"{type_count} atom types", ""]
    lines += [f"{box[0, axis]:.17g} {box[1, axis]:.17g} {_AXES[axis]}lo {_AXES[axis]}hi" for axis in range(3)]
    text = "\n".join(lines) + "\n"
    with open(path, "w") as file:
        file.write(text)
        if count:
            # A section line, one line LAMMPS always skips, then exactly `count` rows: no blank
            # lines and no trailing comments among them (older readers count the words of a row).
            file.write("\nAtoms\n\n" if program == "LIGGGHTS" else "\nAtoms # sphere\n\n")
            table = np.zeros((count, 7))
            table[:, 0] = np.arange(1, count + 1)
            table[:, 1] = types
            table[:, 2] = 2 * radii
            table[:, 3] = rho
            table[:, 4 : 4 + dim] = centers
            np.savetxt(file, table, fmt=["%d", "%d"] + ["%.17g"] * 5)


def read_data(path) -> tuple[np.ndarray, np.ndarray, dict]:
    """Read the spheres of a LAMMPS or LIGGGHTS data file for ``atom_style sphere``.

    What is read: the header's ``atoms`` count and box lines, and the ``Atoms`` section, with
    the style comment ``# sphere`` (or ``# granular``, LIGGGHTS's name) or without one when
    its rows have 7 values (10 with image flags). Rows may carry more values after the seventh,
    such as image flags ``ix iy iz``; they are ignored (the coordinates are kept as written,
    not unwrapped), as is a trailing ``# comment``. ``Velocities`` and every other section are
    skipped. A box tilt line ``xy xz yz`` is accepted when all three are 0 and refused
    otherwise (a triclinic box), as is a general triclinic box (``avec`` ...).

    The spheres come back in the order of their atom IDs; radii are half the diameters. The
    file is 2-D when a header comment says ``dimension 2`` (as ndpack writes it) and every z is
    0; else 3-D.

    Returns
    -------
    centers : (n, d) float64
        ``d`` is 2 or 3.
    radii : (n,) float64
    info : dict
        ``box`` ``(2, 3)`` float64 (LAMMPS's defaults -0.5 and 0.5 where a line is missing),
        ``density`` ``(n,)`` float64, ``ids`` and ``types`` ``(n,)`` int64, in the same order as the spheres,
        and ``periodic`` ``(3,)`` bool: the axes that a header comment ``boundary p p p`` (the
        input script's line, which ndpack writes there) calls periodic; none without one.

    Raises
    ------
    ValueError
        Starting "it ...", for a file that is not such a data file: another atom style, a
        triclinic box, an Atoms section with fewer rows than the header's atom count.
    """
    lines = Path(path).read_text().splitlines()
    if not lines:
        raise ValueError("it is empty")
    comments = [lines[0]]  # the title, which LAMMPS always skips
    natoms, box, body_start = None, np.array([[-0.5] * 3, [0.5] * 3]), len(lines)
    for number, raw in enumerate(lines[1:], start=1):
        content, _, comment = raw.partition("#")
        words = content.split()
        if not words:
            comments.append(comment)
            continue
        if not _is_number(words[0]):
            body_start = number
            break
        count = next((i for i, word in enumerate(words) if not _is_number(word)), len(words))
        values, keyword = words[:count], " ".join(words[count:])
        if keyword == "atoms":
            natoms = _count(values, raw, number)
        elif keyword in ("xlo xhi", "ylo yhi", "zlo zhi"):
            if len(values) != 2:
                raise ValueError(f"its header line {number + 1} ({raw.strip()!r}) needs 2 numbers")
            axis = _AXES.index(keyword[0])
            box[:, axis] = [float(value) for value in values]
        elif keyword == "xy xz yz":
            tilt = [float(value) for value in values]
            if len(tilt) != 3 or any(tilt):
                raise ValueError(f"it has a triclinic box (xy xz yz = {' '.join(values)}); ndpack reads "
                                 "orthogonal boxes only")
        elif keyword in ("avec", "bvec", "cvec", "abc origin"):
            raise ValueError("it has a general triclinic box (avec, bvec, cvec); ndpack reads orthogonal boxes only")
    if natoms is None:
        natoms = 0  # LAMMPS's default; the arrays are sized by the rows found, never by this count
    rows, style, section = None, None, None
    for number in range(body_start, len(lines)):
        content, _, comment = lines[number].partition("#")
        words = content.split()
        if not words:
            continue
        if not _is_number(words[0]):
            section = " ".join(words)
            if section == "Atoms":
                if rows is not None:
                    raise ValueError("it has two Atoms sections")
                rows, style = [], comment.split()[0] if comment.split() else None
            continue
        if section is None:
            raise ValueError(f"its line {number + 1} holds numbers outside any section")
        if section == "Atoms":
            rows.append((number + 1, words))
    if rows is None:
        if natoms:
            raise ValueError(f"its header says {natoms} atoms but it has no Atoms section")
        rows = []
    if len(rows) != natoms:
        what = "truncated" if len(rows) < natoms else "inconsistent"
        raise ValueError(f"it is {what}: its header says {natoms} atoms, its Atoms section has {len(rows)} rows")
    _check_style(style, rows)
    table = np.empty((len(rows), 5))
    ids = np.empty(len(rows), dtype=np.int64)
    types = np.empty(len(rows), dtype=np.int64)
    for i, (number, words) in enumerate(rows):
        try:
            ids[i], types[i] = int(words[0]), int(words[1])
            table[i] = [float(word) for word in words[2:7]]
        except (ValueError, OverflowError):
            raise ValueError(f"its line {number} is not an atom_style sphere row ({' '.join(SPHERE_COLUMNS)}): "
                             f"{' '.join(words)!r}") from None
    order = np.argsort(ids, kind="stable")
    if len(ids) and (np.diff(ids[order]) == 0).any() and ids.any():
        twice = int(ids[order][1:][np.diff(ids[order]) == 0][0])
        raise ValueError(f"its atom ID {twice} is used twice")
    ids, table, types = ids[order], table[order], types[order]
    centers = table[:, 2:5]
    if any(_DIMENSION_2.search(text) for text in comments) and not centers[:, 2].any():
        centers = centers[:, :2]
    centers = np.ascontiguousarray(centers)
    periodic = np.zeros(3, dtype=bool)
    for text in comments:
        styles = _BOUNDARY.search(text)
        if styles:
            periodic = np.array([style == "p" for style in styles.groups()])
    return centers, table[:, 0] / 2, {"box": box, "density": table[:, 1].copy(), "ids": ids, "types": types,
                                      "periodic": periodic}


# ---------------------------------------------------------------------------------- Yade
def write_yade(path, centers, radii, cell=None) -> None:
    """Write 3-D spheres as Yade's text format, read by ``yade.ymport.text(path)``.

    The first line is ``#format x_y_z_r``; then a comment line (and the cell's, for a periodic
    cell), then ``x y z r`` a sphere with 17 significant digits.

    Parameters
    ----------
    path : str or Path
    centers : (n, 3) float64
    radii : (n,) float64
    cell : (2, 3) array_like, optional
        A periodic cell's lower and upper corners: written as a comment with the lines of a Yade
        script that set it, ``O.periodic = True; O.cell.setBox(Lx, Ly, Lz)`` (Yade's cell starts
        at the origin: shift by the lower corner, also written, where it is not 0).
    """
    centers = np.asarray(centers, dtype=np.float64)
    radii = np.asarray(radii, dtype=np.float64).reshape(-1)
    dim = _check_spheres(centers, radii)
    if dim != 3:
        raise DimensionError(f"Yade's text format (x y z r) holds 3-D spheres, not a {dim}-D packing")
    header = f"#format x_y_z_r\n# ndpack: {len(radii)} spheres, one a line: x y z radius\n"
    if cell is not None:
        lower, upper = np.asarray(cell, dtype=np.float64).reshape(2, 3)
        sizes = ", ".join(f"{length:.17g}" for length in upper - lower)
        corner = " ".join(f"{value:.17g}" for value in lower)
        header += f"# periodic cell: O.periodic = True; O.cell.setBox({sizes}); lower corner {corner}\n"
    with open(path, "w") as file:
        file.write(header)
        if len(radii):
            np.savetxt(file, np.column_stack([centers, radii]), fmt="%.17g")


#: The cell comment :func:`write_yade` writes.
_YADE_CELL = re.compile(r"^#\s*periodic cell: O\.periodic = True; O\.cell\.setBox\(([^)]*)\); lower corner (.*)$")


def yade_cell(path) -> np.ndarray | None:
    """The periodic cell (2, 3) of a Yade text file that :func:`write_yade` gave one, else None."""
    for line in Path(path).read_text().splitlines():
        if not line.startswith("#"):
            break
        found = _YADE_CELL.match(line.strip())
        if found:
            try:
                sizes = [float(value) for value in found.group(1).split(",")]
                lower = [float(value) for value in found.group(2).split()]
            except ValueError:
                return None
            if len(sizes) == 3 and len(lower) == 3 and all(math.isfinite(v) and v > 0 for v in sizes):
                return np.array([lower, np.add(lower, sizes)])
    return None


def read_yade(path) -> tuple[np.ndarray, np.ndarray]:
    """Read spheres from a Yade text file (``yade.export.text`` or :func:`write_yade`).

    Lines starting with ``#`` are comments, except ``#format NAME``, which sets the columns for
    the lines after it as Yade does: ``x_y_z_r`` (the default), ``x_y_z_r_matId`` and
    ``x_y_z_r_attrs`` read the first 4 columns, ``id_x_y_z_r_matId`` the 2nd to 5th. Other
    columns, and blank lines, are ignored.

    Returns
    -------
    centers : (n, 3) float64
    radii : (n,) float64

    Raises
    ------
    ValueError
        Starting "it ...": an unknown ``#format``, a row with too few numbers.
    """
    starts = {"x_y_z_r": 0, "x_y_z_r_matId": 0, "x_y_z_r_attrs": 0, "id_x_y_z_r_matId": 1}
    start, rows = 0, []
    for number, line in enumerate(Path(path).read_text().splitlines(), start=1):
        words = line.split()
        if not words:
            continue
        if words[0] == "#format":
            if len(words) < 2 or words[1] not in starts:
                given = words[1] if len(words) > 1 else "nothing"
                raise ValueError(f"its line {number} names the format {given}; ndpack reads "
                                 f"{', '.join(starts)}")
            start = starts[words[1]]
            continue
        if words[0].startswith("#"):
            continue
        try:
            rows.append([float(word) for word in words[start : start + 4]])
        except ValueError:
            rows.append([])
        if len(rows[-1]) != 4:
            raise ValueError(f"its line {number} is not 'x y z r' numbers: {line.strip()!r}")
    table = np.array(rows, dtype=np.float64).reshape(-1, 4)
    return np.ascontiguousarray(table[:, :3]), table[:, 3].copy()


# ---------------------------------------------------------------------------------- helpers
def _check_spheres(centers: np.ndarray, radii: np.ndarray) -> int:
    if centers.ndim != 2 or len(centers) != len(radii):
        raise DimensionError(f"centres of shape (n, d) and radii of shape (n,) are needed, got {centers.shape} "
                             f"and {radii.shape}")
    return centers.shape[1]


def _density_note(program: str, dim: int, density: float) -> str:
    if program == "LIGGGHTS" and dim == 2:
        return (f"density {density:.17g}: mass per area; LIGGGHTS sets each mass to density * pi r^2 in 2-D "
                "(a disc)")
    note = f"density {density:.17g}: mass per volume; {program} sets each mass to density * 4/3 pi r^3"
    if dim == 2:
        note += " (a ball, in 2-D too; `set density/disc` makes discs of mass density * pi r^2)"
    return note


def _boundary_note(program: str, dim: int, periodic: np.ndarray) -> str:
    letters = ["p" if flag else "f" for flag in periodic]
    if dim == 2:
        letters[2] = "p"  # both programs need a periodic z in 2-D
    axes = [_AXES[axis] for axis in range(dim) if periodic[axis]]
    where = f"periodic in {' '.join(axes)}: the box edges there are the periods" if axes else "no periodic axis"
    return f"{where}; in the input script: boundary {' '.join(letters)}"


def _is_number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def _count(values: list[str], raw: str, number: int) -> int:
    try:
        count = int(values[0]) if len(values) == 1 else -1
    except ValueError:
        count = -1
    if count < 0:
        raise ValueError(f"its header line {number + 1} ({raw.strip()!r}) is not a count of atoms")
    return count


def _check_style(style: str | None, rows: list) -> None:
    """Refuse an Atoms section of another atom style, named or told by its rows' lengths."""
    if style is not None and style not in ("sphere", "granular"):
        raise ValueError(f"its Atoms section is for atom_style {style}, not sphere")
    for number, words in rows:
        if len(words) < 7:
            raise ValueError(f"its line {number} has {len(words)} values; an atom_style sphere row has 7 "
                             f"({' '.join(SPHERE_COLUMNS)})")
        if style is None and len(words) not in (7, 10):
            raise ValueError(f"its Atoms section names no atom style and its line {number} has {len(words)} values, "
                             "not 7 (atom_style sphere) or 10 (with image flags)")


# ---------------------------------------------------------------------------------- the formats
def _dem_box(packing: Packing) -> tuple[np.ndarray, np.ndarray, str]:
    """The data file's box ``(2, 3)``, its periodic axes ``(3,)`` and a comment on where the box came from.

    ``params["bounds"]`` and ``params["period"]`` (a periodic domain's cell and per-axis periods)
    where the packing records them; else the shape's bounds; else the spheres' extent.
    """
    bounds, periods = packing.params.get("bounds"), packing.params.get("period")
    where = "the packing's recorded bounds"
    if bounds is None and packing.shape is not None:
        bounds = np.asarray(packing.shape.bounds, dtype=np.float64)
        where = "the shape's bounds"
        if bounds.shape != (2, packing.dim) or not np.isfinite(bounds).all():
            bounds = None
    if bounds is None:
        where = "the spheres' extent (centre -+ radius)"
    box, periodic = data_box(packing.centers, packing.radii, bounds, periods)
    return box, periodic, f"box: {where}"


def _packing_types(packing: Packing, types: str) -> tuple[np.ndarray, np.ndarray]:
    """The atom types of ``types`` ("classes" or "one"; :func:`size_types`) for a packing: the
    classes of a discrete distribution it records (times its ``scale``), else its distinct radii."""
    if types not in ("classes", "one"):
        raise NdpackError(f"types must be 'classes' (an atom type a size class) or 'one' (type 1 for all), "
                          f"got {types!r}")
    if types == "one":
        return np.ones(len(packing.radii), dtype=np.int64), packing.radii[:1]
    distribution = packing.params.get("distribution")
    classes = None
    if isinstance(distribution, dict) and distribution.get("kind") == "discrete":
        classes = np.asarray(distribution["radii"], dtype=np.float64) * float(packing.params.get("scale") or 1.0)
    return size_types(packing.radii, classes)


def _write_packing_data(packing: Packing, path: Path, program: str, density, types) -> None:
    require_dim(packing.dim, range(2, 4), f"a {program} data file")
    density = density_value(density)
    box, periodic, note = _dem_box(packing)
    kinds, radii = _packing_types(packing, types)
    write_data(path, packing.centers, packing.radii, box, periodic, density, program, [note], kinds, radii)


def _write_lammps(packing: Packing, path: Path, density=1.0, types="classes") -> None:
    """A LAMMPS data file for ``atom_style sphere`` (see :func:`write_data`)."""
    _write_packing_data(packing, path, "LAMMPS", density, types)


def _write_liggghts(packing: Packing, path: Path, density=1.0, types="classes") -> None:
    """The same rows for LIGGGHTS's ``read_data`` (see :func:`write_data`)."""
    _write_packing_data(packing, path, "LIGGGHTS", density, types)


def _read_lammps(path: Path) -> Packing:
    """The spheres, and where the header says ``boundary p ...``, the periodic cell: the box as
    ``params["bounds"]`` and each axis's period (None for an open one) as ``params["period"]``,
    as a periodic packing records them (so ``ndpack verify`` checks it as periodic)."""
    centers, radii, info = read_data(path)
    dim = centers.shape[1]
    params = {}
    if info["periodic"][:dim].any():
        box = info["box"][:, :dim]
        params["bounds"] = box.tolist()
        params["period"] = [float(high - low) if periodic else None
                            for low, high, periodic in zip(box[0], box[1], info["periodic"][:dim])]
    return packing_from({"dim": dim, "params": params}, centers, radii)


def _write_packing_yade(packing: Packing, path: Path) -> None:
    require_dim(packing.dim, range(3, 4), "Yade's text format (.txt)")
    cell = None
    periods = packing.params.get("period")
    if periods is not None and all(period is not None for period in periods):  # Yade's cell wraps every axis
        box, _, _ = _dem_box(packing)
        cell = box
    write_yade(path, packing.centers, packing.radii, cell)


def _read_packing_yade(path: Path) -> Packing:
    centers, radii = read_yade(path)
    cell = yade_cell(path)
    params = {} if cell is None else {"bounds": cell.tolist(), "period": (cell[1] - cell[0]).tolist()}
    return packing_from({"dim": 3, "params": params} if params else None, centers, radii)


# Named with format=, lammps and liggghts take any file name (LAMMPS users often write data.bed).
register(Format("lammps", (".data",), "2-3", "spheres, density, box, a type a size class (LAMMPS read_data, "
                "atom_style sphere)", {"density": "1.0", "types": "classes"}, _write_lammps, _read_lammps,
                any_name=True), default_for=(".data",))
register(Format("liggghts", (".data",), "2-3", "the lammps rows, for LIGGGHTS read_data",
                {"density": "1.0", "types": "classes"}, _write_liggghts, _read_lammps, any_name=True))
register(Format("yade", (".txt",), "3", "spheres, as x y z r lines (Yade ymport.text)", {}, _write_packing_yade,
                _read_packing_yade), default_for=(".txt",))
