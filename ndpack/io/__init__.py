"""Packing files: every format ndpack writes, and reads back, chosen by suffix or by name.

========  ================  ====  ====================================================================
name      suffixes          dims  what is kept
========  ================  ====  ====================================================================
npz       .npz              any   everything: metadata, spheres, rounds, round stats, medial axis
csv       .csv              any   metadata (first line), spheres and rounds
json      .json             any   everything, as plain JSON
ply       .ply              1-3   spheres and rounds (one point per sphere), metadata as a comment
vtp       .vtp              1-3   spheres as VTK points with radius, diameter and round (ParaView)
mesh      .obj .stl .glb    3     an icosphere per sphere: centres and radii (STL, GLB: float32, radii
                                  shrunk by its rounding, so that the spheres read back verify)
sph       .sph              3     spheres as a 2-level sphere tree (sphere-tree toolkit)
curobo    .json .yml .yaml  3     spheres as cuRobo ``collision_spheres`` of one link (JSON or YAML)
lammps    .data             2-3   spheres, a density and a box: LAMMPS ``read_data``, atom_style sphere
liggghts  .data             2-3   the same rows, for LIGGGHTS ``read_data`` (atom_style granular)
yade      .txt              3     spheres as ``x y z r`` lines: Yade's ``ymport.text``
medial    .ply .csv         any   the medial-axis sample (points and radii); .ply up to 3-D
========  ================  ====  ====================================================================

The families, one module each: :mod:`~ndpack.io.native` (npz, csv, json), :mod:`~ndpack.io.ply`,
:mod:`~ndpack.io.vtk` (vtp), :mod:`~ndpack.io.mesh` (sphere surfaces), :mod:`~ndpack.io.sph`,
:mod:`~ndpack.io.curobo`, :mod:`~ndpack.io.dem` (lammps, liggghts, yade, and their array
readers and writers) and :mod:`~ndpack.io.medial`; :mod:`~ndpack.io.metadata` holds what they
share about packings. Each module registers its formats when imported, with
``registry.register(Format(name, suffixes, ...), default_for=suffixes)``
(:mod:`~ndpack.io.registry`); this package imports them all, so a format is there as soon as
``ndpack.io`` is.

:func:`save` picks the format from the suffix (the first name listed for it) unless ``format=``
names one: ``liggghts`` and ``medial`` are only chosen by name, and so is ``curobo`` for a
``.json`` file (``.yml`` and ``.yaml`` are always cuRobo YAML). Named, ``lammps`` and
``liggghts`` take any file name (LAMMPS users often write ``data.bed``). :func:`load` reads
every format but ``medial`` (read with :func:`load_medial`); a ``.json`` file is told apart by
its content. cuRobo YAML is written and read with PyYAML.
Files that hold only spheres load as a :class:`~ndpack.packing.Packing` whose volume is unknown
(NaN, so its fill is NaN), whose rounds are 0, and whose params are empty (a LAMMPS file's
periodic box aside: ``bounds`` and ``period``). What a loader checks before it allocates, and its
limits, are in :mod:`~ndpack.io.limits`.

Every problem (unknown suffix or name, wrong dimension, missing or unreadable file) raises an
:class:`~ndpack.errors.NdpackError` with one line.
"""

from __future__ import annotations

# The registry first, then the format modules in the order of names(): importing one registers it.
from .registry import FORMATS, SUFFIXES, Format, check, load, names, save, table
from . import native, ply, vtk, mesh, sph, curobo, dem, medial  # noqa: F401
from .curobo import curobo_yaml
from .dem import read_data, read_yade, write_data, write_yade
from .medial import load_medial
from .mesh import sphere_mesh, spheres_from_mesh
from .metadata import metadata
from .sph import read_sph
from ..packing import SERVICES

SERVICES.update(save=save, load=load)  # Packing.save and Packing.load (a packing saves itself)

__all__ = [
    "Format", "FORMATS", "SUFFIXES", "save", "check", "load", "load_medial", "names", "table", "sphere_mesh",
    "spheres_from_mesh", "metadata", "read_sph", "curobo_yaml", "read_data", "write_data", "read_yade", "write_yade",
]
