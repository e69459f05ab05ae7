"""Sample files that ship with ndpack: the meshes and the robot the documentation uses.

``ndpack samples`` (or :func:`write`) writes them into a folder, so that every command in the
docs (``ndpack pack cow.obj ...``, ``ndpack cover arm.urdf ...``) works as written on a fresh
install::

    import ndpack.samples
    ndpack.samples.write(".")             # cow.obj, fandisk.obj, armadillo.obj, arm.urdf here
    mesh = ndpack.samples.load("cow")     # or straight to a TriangleMesh

The meshes are small copies (binary PLY inside the package) of public test models; see
:data:`SAMPLES` for what each is. All are closed, and stored as in their OBJ originals:
y up for the cow and the armadillo, z up for the fandisk. ``arm.urdf`` is a four-link arm of
URDF primitives.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from ..errors import ParameterError
from ..shapes.mesh import TriangleMesh

#: name -> what it is: triangles and where it comes from.
SAMPLES = {
    "cow": "5,804 triangles, 10.4 x 6.4 x 3.4, y up (a timing model of the ProtoSphere paper)",
    "fandisk": "12,946 triangles, 4.8 x 5.2 x 2.7, z up (a CAD part: sharp edges, flat faces)",
    "armadillo": "20,000 triangles, 127 x 151 x 115, y up (the Stanford armadillo decimated from 99,976; "
                 "the paper's figure 1)",
}
#: The robot sample, written as ``arm.urdf``.
ROBOT = "arm"
ROBOT_NOTE = "a four-link arm of URDF primitives (cylinders, a box, a sphere), for `ndpack cover`"


def names() -> list[str]:
    """The sample names: ``["cow", "fandisk", "armadillo"]``."""
    return list(SAMPLES)


def path(name: str) -> Path:
    """The packaged file of a sample (binary PLY, read-only: :func:`write` makes an OBJ copy)."""
    _check(name)
    return Path(str(resources.files(__name__) / f"{name}.ply"))


def load(name: str, **options):
    """A sample as a :class:`~ndpack.TriangleMesh` (``options`` as for ``TriangleMesh.load``)."""
    return TriangleMesh.load(path(name), **options)


def write(folder=".", names: list[str] | None = None, suffix: str = ".obj", robot: bool = True) -> list[Path]:
    """Write the sample meshes into ``folder`` (made if missing) as ``<name><suffix>`` (any mesh
    suffix trimesh writes), and the robot as ``arm.urdf`` unless ``robot`` is False.

    Returns
    -------
    list of Path
        The files written: the meshes in the order of ``names`` (default: every one), then the robot.
    """
    import trimesh

    folder = Path(folder).expanduser()
    if folder.exists() and not folder.is_dir():
        raise ParameterError(f"cannot write the samples into {folder}: it is a file, not a folder")
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name in names or list(SAMPLES):
        mesh = trimesh.load(path(name), force="mesh")
        target = folder / f"{name}{suffix}"
        mesh.export(target)
        written.append(target)
    if robot:
        target = folder / f"{ROBOT}.urdf"
        target.write_text((resources.files(__name__) / f"{ROBOT}.urdf").read_text())
        written.append(target)
    return written


def _check(name: str) -> None:
    if name not in SAMPLES:
        raise ParameterError(f"no sample named {name!r}; the samples are {', '.join(SAMPLES)}")
