"""Robots: a URDF in, collision spheres per link out (for cuRobo, MoveIt, VAMP and the like).

:func:`read_urdf_links` reads each ``<link>``'s geometry into ndpack shapes in the link's own
frame; :func:`cover_urdf` covers each link with spheres (:func:`ndpack.cover`) and writes

- ``<robot>_spheres.urdf``: the URDF with each covered link's ``<collision>`` elements replaced by
  one sphere each (``<collision name="<link>_sphere_<i>">``); visuals, joints and everything else
  as they were;
- ``<robot>_spheres.yml``: cuRobo's collision spheres file (``collision_spheres:`` link ->
  ``[{center: [x, y, z], radius: r}, ...]``, see :func:`ndpack.io.curobo_yaml`);
- ``report.json``: per link the sphere count, the largest protrusion (as a length and as a share
  of the link's bounding-box diagonal), whether fresh samples were all covered, and the seconds.

What a link's geometry is
-------------------------
Its ``<collision>`` elements, or its ``<visual>`` ones where it has none. Each element's
``<origin xyz="..." rpy="...">`` places its ``<geometry>`` in the link's frame (URDF's fixed-axis
roll, pitch, yaw: ``R = Rz(yaw) Ry(pitch) Rx(roll)``), after a mesh's ``scale``:

========================================  =======================================================
``<mesh filename="..." scale="...">``     :class:`~ndpack.TriangleMesh` of the scaled, placed
                                          vertices (anything trimesh reads: STL, OBJ, DAE, ...)
``<box size="x y z">``                    :class:`~ndpack.Box` about the origin, rotated, moved
``<cylinder radius="r" length="l">``      :class:`~ndpack.Cylinder` along z, centred
``<sphere radius="r">``                   :class:`~ndpack.Ball`
========================================  =======================================================

Mesh file names: ``package://pkg/path`` is looked up in ``packages={"pkg": folder}`` if given,
then in every folder from the URDF's upwards (a folder named ``pkg``, or one holding a ``pkg``
folder), then in the folders of ``$ROS_PACKAGE_PATH``, then as ``path`` beside the URDF;
``model://`` (Gazebo) the same way; ``file://`` is stripped; a relative name is relative to the
URDF's folder.

Each geometry of a link is covered on its own and the link's spheres are their concatenation (so
each sphere reaches out of its own geometry by at most the protrusion, hence out of the link's).
A link whose geometry cannot be read (a missing or broken mesh) or covered is reported, with a
:class:`RobotWarning`, and keeps its collision elements in the written URDF; the other links are
written all the same.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from ...errors import NdpackError, ParameterError, ShapeError
from ...io import curobo_yaml
from ...meshes import surface
from ...shapes.mesh import TriangleMesh
from ...shapes.primitives import Ball, Box, Cylinder
from .covering import CHECK_SAMPLES, DEFAULT_SAMPLES, Covering, check_covering, cover
from .estimate import MAX_SPHERES, TooManySpheres
from .estimate import refuse_too_many as _refuse_too_many_spheres

#: ``nd.cover`` options :func:`cover_urdf` passes on (the rest are its own, or per shape).
COVER_OPTIONS = ("samples", "check_samples", "backend", "device", "max_spheres")


class RobotWarning(UserWarning):
    """A link of a robot could not be read or covered; the other links were written."""


@dataclass
class LinkGeometry:
    """One link's geometry, as ndpack shapes in the link's frame.

    Attributes
    ----------
    name : str
        The link's name.
    shapes : list of Oracle
        One 3-D shape per geometry element, in the link's frame; empty for a link without
        geometry (or one whose geometry could not be read: see ``error``).
    parts : list of str
        What each shape was, such as ``"mesh meshes/arm.stl"`` or ``"box 0.1 0.2 0.3"``.
    source : {"collision", "visual", None}
        The elements the shapes come from: ``"visual"`` where the link has no collision elements;
        None for a link without either.
    error : str or None
        Why the geometry could not be read (only with ``strict=False``).
    """

    name: str
    shapes: list = field(default_factory=list)
    parts: list = field(default_factory=list)
    source: str | None = None
    error: str | None = None

    @property
    def shape(self):
        """The link's geometry as one shape (the union of :attr:`shapes`), or None if it has none."""
        if not self.shapes:
            return None
        shape = self.shapes[0]
        return shape if len(self.shapes) == 1 else shape.union(*self.shapes[1:])

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) float64: the box enclosing every shape of the link."""
        if not self.shapes:
            raise ShapeError(f"link {self.name!r} has no geometry, hence no bounds")
        boxes = np.array([shape.bounds for shape in self.shapes])
        return np.array([boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)])

    @property
    def diagonal(self) -> float:
        """The length of the diagonal of :attr:`bounds`."""
        return float(np.linalg.norm(np.ptp(self.bounds, axis=0)))


@dataclass
class RobotCovering:
    """What :func:`cover_urdf` made and wrote.

    Attributes
    ----------
    robot : str
        The robot's name (``<robot name=...>``).
    links : dict of str to Covering
        The covered links, in the URDF's order: each one's spheres in the link's frame (those of
        all its geometries together; ``shape`` is their union, ``report`` checks against it).
    failed : dict of str to str
        Links whose geometry could not be read or covered, and why.
    skipped : list of str
        Links without geometry.
    urdf, yaml, report : Path
        The files written: the URDF with sphere collisions, cuRobo's spheres, the JSON report.
    seconds : float
        Wall time of the whole run.
    interrupted : list of str
        Where Ctrl-C stopped the run: the link being covered then, and those after it. They keep
        their collision elements in the written URDF (a link's spheres are written only once its
        covering is whole) and are in the report as ``"interrupted"``; empty for a whole run.
    """

    robot: str
    links: dict
    failed: dict
    skipped: list
    urdf: Path
    yaml: Path
    report: Path
    seconds: float
    interrupted: list = field(default_factory=list)

    @property
    def covered(self) -> bool:
        """Every link was read and covered, and fresh samples of each are all covered."""
        return (not self.failed and not self.interrupted
                and all(covering.report.covered for covering in self.links.values()))

    def summary(self) -> str:
        """A line per link: spheres, largest protrusion (and its share of the link's diagonal),
        covered or not, seconds; the failed links with their reason."""
        width = max([len(name) for name in [*self.links, *self.failed]] + [4])
        lines = [f"robot {self.robot!r}: {len(self.links)} links covered, {len(self.failed)} failed, "
                 f"{len(self.skipped)} without geometry, in {self.seconds:.1f} s",
                 f"  {'link':<{width}}  {'spheres':>7}  {'max protrusion':>14}  {'of diagonal':>11}  {'covered':>7}  "
                 f"{'seconds':>7}"]
        for name, covering in self.links.items():
            report = covering.report
            share = report.max_protrusion / report.diagonal if report.diagonal > 0 else math.nan
            state = "yes" if report.covered else "NO"
            lines.append(f"  {name:<{width}}  {len(covering):>7d}  {report.max_protrusion:>14.4g}  {share:>11.2%}  "
                         f"{state:>7}  {covering.params.get('seconds', math.nan):>7.2f}")
        for name, reason in self.failed.items():
            lines.append(f"  {name.ljust(width)}  FAILED: {reason}")
        if self.interrupted:
            lines.append(f"  INTERRUPTED (Ctrl-C) while covering {self.interrupted[0]!r}: it and the "
                         f"{len(self.interrupted) - 1} links after it keep their collision elements")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return (f"<RobotCovering {self.robot!r}: {len(self.links)} links covered, {len(self.failed)} failed, "
                f"{sum(len(c) for c in self.links.values())} spheres>")


# ------------------------------------------------------------------------------------------- reading
def read_urdf_links(path, *, packages: dict | None = None, holes: str | None = None,
                    strict: bool = True) -> list[LinkGeometry]:
    """Every link of a URDF file with its geometry as ndpack shapes in the link's frame.

    Parameters
    ----------
    path : str or Path
        A URDF file (expand a ``.xacro`` file first: ``xacro robot.urdf.xacro > robot.urdf``).
    packages : dict of str to path, optional
        Folders of ROS packages, for ``package://name/...`` mesh names the search (see the module's
        docstring) does not find.
    holes : {"cap", "refuse"}, optional
        What to do with an open mesh (:class:`~ndpack.TriangleMesh`); default: cap, with a
        :class:`~ndpack.MeshWarning`.
    strict : bool
        Raise :class:`~ndpack.ShapeError` for a link whose geometry cannot be read (naming the
        link and, for a mesh, the file); False records it in the link's ``error`` instead.

    Returns
    -------
    list of LinkGeometry
        One per ``<link>``, in the file's order, those without geometry included.
    """
    path = Path(path)
    root = _parse_urdf(path)
    links = []
    for element in root.findall("link"):
        name = element.get("name")
        if not name:
            raise ShapeError(f"{path}: a <link> has no name")
        geometry = LinkGeometry(name)
        elements = element.findall("collision")
        geometry.source = "collision" if elements else None
        if not elements:
            elements = element.findall("visual")
            geometry.source = "visual" if elements else None
        try:
            for item in elements:
                shape, part = _geometry_shape(item, path.parent, packages, holes)
                geometry.shapes.append(shape)
                geometry.parts.append(part)
        except NdpackError as error:
            message = f"link {name!r}: {' '.join(str(error).split())}"
            if strict:
                raise ShapeError(message) from error
            geometry.shapes, geometry.parts, geometry.error = [], [], message
        links.append(geometry)
    return links


def _parse_urdf(path: Path) -> ET.Element:
    if path.name.lower().endswith(".xacro"):
        raise ShapeError(f"{path} is a xacro file: expand it to URDF first (xacro {path.name} > robot.urdf)")
    if not path.is_file():
        raise ShapeError(f"no URDF file at {path}" if not path.exists() else f"{path} is a folder, not a URDF file")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as error:
        raise ShapeError(f"{path} is not valid XML ({error})") from None
    if root.tag != "robot":
        raise ShapeError(f"{path} is not a URDF file: its root element is <{root.tag}>, not <robot>")
    return root


def rpy_matrix(rpy) -> np.ndarray:
    """URDF's rotation of roll, pitch and yaw (radians) about the fixed x, y and z axes.

    Returns
    -------
    (3, 3) float64
        ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``: a point ``p`` of the child frame is ``R @ p + xyz``.
    """
    from scipy.spatial.transform import Rotation

    # Lower-case axes are SciPy's extrinsic (fixed) ones: x first, so R = Rz @ Ry @ Rx.
    return Rotation.from_euler("xyz", [float(angle) for angle in rpy]).as_matrix()


def _numbers(element: ET.Element, attribute: str, count: int, default=None, what: str = "") -> np.ndarray:
    """An attribute of ``count`` numbers (or one, repeated, where ``count`` is 3 and one is given
    for a mesh scale)."""
    text = element.get(attribute)
    if text is None:
        if default is None:
            raise ShapeError(f"<{element.tag}> has no {attribute}=")
        return np.asarray(default, dtype=np.float64)
    try:
        values = np.array([float(part) for part in text.split()], dtype=np.float64)
    except ValueError:
        values = np.array([math.nan])
    if what == "scale" and len(values) == 1:
        values = np.repeat(values, 3)
    if len(values) != count or not np.all(np.isfinite(values)):
        raise ShapeError(f"<{element.tag} {attribute}={text!r}> must be {count} finite number"
                         f"{'s' if count > 1 else ''}")
    return values


def _positive(element: ET.Element, attribute: str, count: int = 1) -> np.ndarray:
    values = _numbers(element, attribute, count)
    if not np.all(values > 0):
        raise ShapeError(f"<{element.tag} {attribute}={element.get(attribute)!r}> must be positive")
    return values


def _geometry_shape(item: ET.Element, folder: Path, packages, holes):
    """The shape of a ``<collision>`` or ``<visual>`` element in the link's frame, and what it was."""
    origin = item.find("origin")
    xyz = np.zeros(3) if origin is None else _numbers(origin, "xyz", 3, np.zeros(3))
    rpy = np.zeros(3) if origin is None else _numbers(origin, "rpy", 3, np.zeros(3))
    rotation = rpy_matrix(rpy)
    turned = bool(np.any(rpy != 0))
    geometry = item.find("geometry")
    kinds = [child for child in (geometry if geometry is not None else []) if isinstance(child.tag, str)]
    if geometry is None or not kinds:
        raise ShapeError(f"a <{item.tag}> has no <geometry> with a shape in it")
    shape = kinds[0]
    if shape.tag == "mesh":
        filename = shape.get("filename")
        if not filename:
            raise ShapeError("a <mesh> has no filename=")
        scale = _numbers(shape, "scale", 3, np.ones(3), what="scale")
        if not np.all(scale != 0):
            raise ShapeError(f"<mesh scale={shape.get('scale')!r}> must not be 0 along any axis")
        mesh_path = resolve_mesh(filename, folder, packages)
        mesh = surface.read(mesh_path)
        vertices = (np.asarray(mesh.vertices, dtype=np.float64) * scale) @ rotation.T + xyz
        faces = np.asarray(mesh.faces, dtype=np.int64)
        if np.prod(np.sign(scale)) < 0:  # a mirroring scale turns the triangles inside out
            faces = faces[:, ::-1]
        part = f"mesh {filename}" + ("" if np.all(scale == 1) else f" (scale {' '.join(map(repr, scale.tolist()))})")
        return TriangleMesh(vertices, faces, name=mesh_path.name, holes=holes), part
    if shape.tag == "box":
        size = _positive(shape, "size", 3)
        solid = Box(-size / 2, size / 2)
        if turned:
            solid = solid.rotate(rotation)
        if np.any(xyz != 0):
            solid = solid.translate(xyz)
        return solid, f"box {' '.join(map(repr, size.tolist()))}"
    if shape.tag == "cylinder":
        radius, length = float(_positive(shape, "radius")[0]), float(_positive(shape, "length")[0])
        axis = rotation @ np.array([0.0, 0.0, length / 2])
        return Cylinder(xyz - axis, xyz + axis, radius), f"cylinder r={radius!r} l={length!r}"
    if shape.tag == "sphere":
        radius = float(_positive(shape, "radius")[0])
        return Ball(xyz, radius), f"sphere r={radius!r}"
    raise ShapeError(f"<{shape.tag}> is not a URDF geometry ndpack reads (mesh, box, cylinder, sphere)")


def resolve_mesh(filename: str, folder, packages: dict | None = None) -> Path:
    """The file a URDF's ``<mesh filename=...>`` names (see the module's docstring for the search).

    Parameters
    ----------
    filename : str
        ``package://pkg/path``, ``model://model/path``, ``file:///abs/path``, or a path.
    folder : str or Path
        The URDF's folder.
    packages : dict of str to path, optional
        Package folders to try first.

    Returns
    -------
    Path
        An existing file. Raises :class:`~ndpack.ShapeError`, naming the places tried, otherwise.
    """
    folder = Path(folder).resolve()
    tried = []
    for scheme in ("package://", "model://"):
        if filename.startswith(scheme):
            package, _, rest = unquote(filename[len(scheme):]).partition("/")
            candidates = []
            if packages and package in packages:
                candidates.append(Path(packages[package]).expanduser() / rest)
            for place in (folder, *folder.parents):
                if place.name == package:
                    candidates.append(place / rest)
                candidates.append(place / package / rest)
            for entry in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep):
                if entry:
                    entry = Path(entry).expanduser()
                    candidates += [entry / package / rest] + ([entry / rest] if entry.name == package else [])
            candidates.append(folder / rest)
            for candidate in candidates:
                if candidate.is_file():
                    return candidate
            tried = [f"a folder {package!r} at or above {folder}", f"{folder / rest}"]
            if packages:
                tried.insert(0, f"packages[{package!r}]")
            if os.environ.get("ROS_PACKAGE_PATH"):
                tried.append("$ROS_PACKAGE_PATH")
            raise ShapeError(f"mesh file {filename!r} not found (tried {', '.join(tried)}): pass "
                             f"packages={{{package!r}: folder}} (ndpack cover --package {package}=FOLDER)")
    name = unquote(filename[len("file://"):]) if filename.startswith("file://") else filename
    candidate = Path(name).expanduser()
    if not candidate.is_absolute():
        candidate = folder / candidate
    if candidate.is_file():
        return candidate
    raise ShapeError(f"mesh file {filename!r} not found (looked for {candidate})")


# ------------------------------------------------------------------------------------------ covering
def cover_urdf(path, out_dir, *, n: int | None = None, protrusion: float | None = None,
               protrusion_share: float | None = None, packages: dict | None = None, holes: str | None = None,
               seed: int = 0, progress: bool | None = None, **cover_options) -> RobotCovering:
    """Cover every link of a URDF with spheres and write them for robot software.

    Parameters
    ----------
    path : str or Path
        The URDF file.
    out_dir : str or Path
        The folder to write ``<robot>_spheres.urdf``, ``<robot>_spheres.yml`` and ``report.json``
        into (made if missing). A name with a suffix (``arm.yml``) that is not a folder already is
        refused as a file name; end it with ``/`` for a new folder so named (``"arm.v2/"``).
    n : int, optional
        Spheres per link, protruding as little as that allows. A link of several geometries
        shares them out by each one's bounding-box diagonal, one at least each (so a link of more
        geometries than ``n`` gets one a geometry).
    protrusion : float, optional
        The farthest a sphere may reach outside its link, as a length (the URDF's unit, metres).
    protrusion_share : float, optional
        The same, as a share of each link's bounding-box diagonal: ``0.01`` lets the spheres of a
        link 50 cm across reach 5 mm out, those of a 5 cm finger 0.5 mm. Give one of ``n``,
        ``protrusion`` and ``protrusion_share``.
    packages : dict of str to path, optional
        Folders of ROS packages (see :func:`read_urdf_links`).
    holes : {"cap", "refuse"}, optional
        What to do with open meshes (see :func:`read_urdf_links`).
    seed : int
        Seed of every covering.
    progress : bool, optional
        A progress bar over the links; by default only when stderr is a terminal.
    **cover_options
        ``samples``, ``check_samples``, ``backend``, ``device`` and ``max_spheres``, as for
        :func:`ndpack.cover`.

    Returns
    -------
    RobotCovering
        The coverings per link (spheres in the link's frame) and the paths written. Links that
        could not be read or covered are in its ``failed`` (and the report), each with a
        :class:`RobotWarning`; they keep their collision elements in the written URDF. Ctrl-C
        stops the run within a second or so: the links covered by then are written (the files
        and report as for a whole run), the rest are in its ``interrupted``.

    Raises
    ------
    ndpack.drivers.collision.estimate.TooManySpheres
        Before any link is covered, where the protrusion calls for more spheres on a link than
        ``max_spheres`` or ``samples`` (see :func:`ndpack.cover`), naming the link.
    """
    from tqdm.auto import tqdm

    started = time.perf_counter()
    asked = [name for name, value in (("n", n), ("protrusion", protrusion), ("protrusion_share", protrusion_share))
             if value is not None]
    if len(asked) != 1:
        raise ParameterError("give one of n (spheres per link), protrusion (a length) and protrusion_share (a share "
                             f"of each link's bounding-box diagonal); got {', '.join(asked) or 'none'}")
    if n is not None and (isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1):
        raise ParameterError(f"n must be a positive integer (spheres per link), got {n!r}")
    for name, value in (("protrusion", protrusion), ("protrusion_share", protrusion_share)):
        if value is not None and not (isinstance(value, (int, float, np.floating)) and math.isfinite(value)
                                      and value > 0):
            raise ParameterError(f"{name} must be a positive number, got {value!r}")
    unknown = sorted(set(cover_options) - set(COVER_OPTIONS))
    if unknown:
        raise ParameterError(f"cover_urdf takes no option {', '.join(unknown)} (its cover options: "
                             f"{', '.join(COVER_OPTIONS)})")
    path = Path(path)
    root = _parse_urdf(path)
    robot = root.get("name") or path.stem
    out_dir = _out_dir(out_dir)
    links = read_urdf_links(path, packages=packages, holes=holes, strict=False)
    if n is None:
        _refuse_too_many(links, protrusion, protrusion_share, cover_options)
    out_dir.mkdir(parents=True, exist_ok=True)

    coverings, failed, skipped, entries, interrupted = {}, {}, [], {}, []
    show = sys.stderr.isatty() if progress is None else progress
    bar = tqdm(links, desc="covering links", disable=not show, dynamic_ncols=True, unit="link")
    for index, link in enumerate(bar):
        bar.set_postfix_str(link.name)
        if link.error is None and not link.shapes:
            skipped.append(link.name)
            continue
        link_started = time.perf_counter()
        try:
            if link.error is not None:
                raise ShapeError(link.error.removeprefix(f"link {link.name!r}: "))
            covering = _cover_link(link, n, protrusion, protrusion_share, seed, cover_options)
        except KeyboardInterrupt:  # keep the links done; this one and the rest keep their elements
            interrupted = [item.name for item in links[index:] if item.error is not None or item.shapes]
            for name in interrupted:
                entries[name] = {"status": "interrupted"}
            break
        except NdpackError as error:
            reason = " ".join(str(error).split())
            failed[link.name] = reason
            entries[link.name] = {"status": "failed", "error": reason, "source": link.source,
                                  "seconds": time.perf_counter() - link_started}
            warnings.warn(f"{path.name}: link {link.name!r} was not covered ({reason}); its collision elements are "
                          "kept as they were", RobotWarning, stacklevel=2)
            continue
        coverings[link.name] = covering
        report = covering.report
        entries[link.name] = {
            "status": "covered" if report.covered else "not covered",
            "source": link.source, "parts": list(link.parts), "spheres": len(covering),
            "max_protrusion": report.max_protrusion, "diagonal": report.diagonal,
            "relative_protrusion": report.max_protrusion / report.diagonal if report.diagonal > 0 else None,
            "covered": report.covered, "worst_gap": report.worst_gap,
            "notes": covering.notes, "seconds": covering.params["seconds"],
        }
    bar.close()

    urdf_out = out_dir / f"{_file_name(robot)}_spheres.urdf"
    yaml_out = out_dir / f"{_file_name(robot)}_spheres.yml"
    report_out = out_dir / "report.json"
    _write_sphere_urdf(path, urdf_out, coverings)
    yaml_out.write_text(curobo_yaml({name: (c.centers, c.radii) for name, c in coverings.items()},
                                    comment=f"cuRobo collision spheres of {robot!r} ({path.name}), written by ndpack: "
                                    "each link's spheres in its own frame"))
    seconds = time.perf_counter() - started
    request = {"n": None if n is None else int(n), "protrusion": None if protrusion is None else float(protrusion),
               "protrusion_share": None if protrusion_share is None else float(protrusion_share),
               "seed": int(seed), **{key: value for key, value in cover_options.items()
                                     if key in ("samples", "check_samples")}}
    document = {"robot": robot, "urdf": str(path), "request": request,
                "outputs": {"urdf": urdf_out.name, "yaml": yaml_out.name},
                "covered": not failed and not interrupted and all(c.report.covered for c in coverings.values()),
                "seconds": seconds, "links": entries, "failed": sorted(failed), "without_geometry": skipped,
                "interrupted": interrupted}
    report_out.write_text(json.dumps(document, indent=2) + "\n")
    return RobotCovering(robot, coverings, failed, skipped, urdf_out, yaml_out, report_out, seconds, interrupted)


def _out_dir(out_dir) -> Path:
    """``out_dir`` as a folder to write into: not a file, and not a name with a suffix unless it is
    a folder already or ends with a separator (``-o arm.yml`` meant a file, and a robot writes three)."""
    text = os.fspath(out_dir)
    folder = Path(text).expanduser()
    if folder.exists() and not folder.is_dir():
        raise ParameterError(f"{text} is a file: give a folder to write the robot's spheres into")
    if folder.suffix and not folder.is_dir() and not text.endswith(("/", os.sep)):
        raise ParameterError(f"{text} looks like a file name (it ends in {folder.suffix}), but a robot's spheres are "
                             f"three files written into a folder: <robot>_spheres.urdf, <robot>_spheres.yml and "
                             f"report.json; give a folder, e.g. {folder.with_suffix('')}_spheres/ (end a folder's "
                             f"name with / to keep a suffix: {text}/)")
    return folder


def _refuse_too_many(links, protrusion, protrusion_share, options) -> None:
    """:class:`~ndpack.drivers.collision.estimate.TooManySpheres` before any work where a link's protrusion
    calls for more spheres than ``max_spheres`` or ``samples`` (as :func:`ndpack.cover` would, link by link)."""
    max_spheres = options.get("max_spheres", MAX_SPHERES)
    samples = options.get("samples", DEFAULT_SAMPLES)
    for link in links:
        if link.error is not None or not link.shapes:
            continue
        length = protrusion if protrusion_share is None else protrusion_share * link.diagonal
        for shape in link.shapes:
            try:
                _refuse_too_many_spheres(shape, float(length), max_spheres, int(samples))
            except TooManySpheres as error:
                error.subject = f"link {link.name!r} ({shape!r})"
                if protrusion_share is not None:  # the share is of the link's diagonal
                    error.diagonal = link.diagonal
                raise


def _file_name(name: str) -> str:
    """A robot's name as a file name: path separators and odd characters become ``_``."""
    cleaned = "".join(char if char.isalnum() or char in "-_." else "_" for char in name).strip(".")
    return cleaned or "robot"


def _cover_link(link: LinkGeometry, n, protrusion, protrusion_share, seed, options):
    """One Covering of all of a link's geometries: each covered on its own, the spheres joined."""
    started = time.perf_counter()
    shapes = link.shapes
    if protrusion_share is not None:
        protrusion = protrusion_share * link.diagonal
    counts = [None] * len(shapes) if n is None else _share_out(n, [shape.diagonal for shape in shapes])
    parts = []
    for shape, count in zip(shapes, counts):
        parts.append(cover(shape, n=count, protrusion=protrusion, seed=seed, progress=False, **options))
        if parts[-1].interrupted:  # a link's spheres are written whole, or not at all
            raise KeyboardInterrupt
    if len(parts) == 1:
        covering = parts[0]
        covering.params["seconds"] = time.perf_counter() - started
        return covering
    centers = np.vstack([part.centers for part in parts])
    radii = np.concatenate([part.radii for part in parts])
    union = link.shape
    check = options.get("check_samples", CHECK_SAMPLES)
    report = check_covering(union, centers, radii, samples=check, seed=seed + 1)
    protrusions = np.maximum(radii + union.distance(centers), 0.0)  # as Covering.protrusion: r + f(c)
    params = {"n": None if n is None else int(n), "protrusion": protrusion, "seed": int(seed),
              "parts": [part.params for part in parts], "seconds": time.perf_counter() - started}
    return Covering(centers, radii, protrusions, report, params, union)


def _share_out(n: int, weights) -> list[int]:
    """``n`` shared out in proportion to ``weights`` (largest remainders), at least 1 each."""
    weights = np.asarray(weights, dtype=np.float64)
    if n <= len(weights):
        return [1] * len(weights)
    ideal = (n - len(weights)) * weights / weights.sum()
    counts = np.floor(ideal).astype(np.int64)
    order = np.argsort(-(ideal - counts), kind="stable")
    counts[order[: (n - len(weights)) - int(counts.sum())]] += 1
    return [int(count) + 1 for count in counts]


# ------------------------------------------------------------------------------------------- writing
def _write_sphere_urdf(source: Path, target: Path, coverings: dict) -> None:
    """A copy of the URDF in which each covered link's ``<collision>`` elements are its spheres.

    Comments, processing instructions and namespace prefixes are kept; each new element is
    indented like the link's other children. Numbers are written with ``repr`` (every bit).
    """
    for _, (prefix, uri) in ET.iterparse(source, events=("start-ns",)):
        try:
            ET.register_namespace(prefix, uri)
        except ValueError:  # a reserved prefix (ns0, ...): ElementTree names it itself
            pass
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True, insert_pis=True))
    tree = ET.parse(source, parser)
    for link in tree.getroot().findall("link"):
        covering = coverings.get(link.get("name"))
        if covering is not None:
            _replace_collisions(link, link.get("name"), covering.centers, covering.radii)
    tree.write(target, encoding="utf-8", xml_declaration=True)
    with open(target, "a", encoding="utf-8") as file:
        file.write("\n")


def _replace_collisions(link: ET.Element, name: str, centers, radii) -> None:
    children = list(link)
    old = [child for child in children if child.tag == "collision"]
    position = children.index(old[0]) if old else len(children)
    closing = children[-1].tail if children else None
    for child in old:
        link.remove(child)
    indent = link.text if link.text is not None and not link.text.strip() else ""
    step = "  " if "\n" in indent else ""
    new = []
    for i, (center, radius) in enumerate(zip(np.asarray(centers).tolist(), np.asarray(radii).tolist())):
        collision = ET.Element("collision", {"name": f"{name}_sphere_{i}"})
        collision.text = indent + step
        origin = ET.SubElement(collision, "origin", {"xyz": " ".join(repr(float(x)) for x in center), "rpy": "0 0 0"})
        origin.tail = indent + step
        geometry = ET.SubElement(collision, "geometry")
        geometry.text = indent + 2 * step
        sphere = ET.SubElement(geometry, "sphere", {"radius": repr(float(radius))})
        sphere.tail = indent + step
        geometry.tail = indent
        new.append(collision)
    for offset, collision in enumerate(new):
        link.insert(position + offset, collision)
    children = list(link)
    if not children:
        return
    if link.text is None or not link.text.strip():
        link.text = indent or link.text
    for child in children[:-1]:
        if child.tail is None or not child.tail.strip():
            child.tail = indent or child.tail
    if closing is not None and not closing.strip():
        children[-1].tail = closing
    elif not children[-1].tail or not children[-1].tail.strip():
        children[-1].tail = indent[:-len(step)] if step and indent.endswith(step) else indent


__all__ = ["LinkGeometry", "RobotCovering", "RobotWarning", "cover_urdf", "read_urdf_links", "resolve_mesh",
           "rpy_matrix"]
