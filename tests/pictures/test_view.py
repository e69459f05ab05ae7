"""Which way is up: packings stand on their base (the six test meshes, a scan stored z-up in
an OBJ file), an asked-for axis overrides it, and ``picture(...).up`` says which and why."""

import os
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

import ndpack as nd
from ndpack.pictures import choose_up, picture
from ndpack.pictures.view import bases

#: The six test meshes: the checkout's copies of ../shared/data/meshes (tests/data/meshes/README.md:
#: the same frames, two of them decimated), so that CI checks them too.
MESHES = Path(__file__).resolve().parents[1] / "data" / "meshes"
FILES = {"armadillo": "armadillo-20k.ply", "cow": "cow.ply", "spot": "spot-unwelded.ply",
         "stanford-bunny": "stanford-bunny-12k.ply", "fandisk": "fandisk.ply", "rocker-arm": "rocker-arm.ply"}

#: Which way each mesh stands, read off renders with each of the six ups side by side (and
#: standing in docs/img/standing.png, made by bench/standing.py).
STANDING = {
    "armadillo": "y",  # on its two feet at -y, y up (the Stanford scan's own frame)
    "cow": "y",  # on its four hooves at -y; x runs nose to tail
    "spot": "y",  # Keenan Crane's cow: four short legs at -y
    "stanford-bunny": "y",  # on its flat, open base at -y
    "fandisk": "-z",  # the CAD part's broad flat face is at +z: it stands on it upside down, -z up
    "rocker-arm": "x",  # a lever lying flat on a broad side; its other side (-x) is nearly as broad
}


def pack_small(mesh, seed=0):
    """200 spheres, coarse grid: a second or so a mesh, and enough to show the base."""
    return nd.pack(mesh, n=200, seed=seed, mode="fast", grid=12)


def load(path):
    with warnings.catch_warnings():  # the bunny is open: its holes are capped, with a warning
        warnings.simplefilter("ignore", nd.MeshWarning)
        return nd.TriangleMesh.load(path)


def spheres(centers, radii, **params):
    centers = np.asarray(centers, dtype=np.float64)
    packing = nd.Packing(centers, np.asarray(radii, dtype=np.float64), np.zeros(len(centers), dtype=np.int64), 1.0)
    packing.params.update(params)
    return packing


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(STANDING))
def test_each_test_mesh_stands_on_its_base(name):
    mesh = load(MESHES / FILES[name])
    mesh.name = None  # the spheres alone decide, not the .obj convention
    packing = pack_small(mesh)
    chosen = choose_up(packing)
    assert chosen.name == STANDING[name], str(chosen)
    assert chosen.reason.startswith("it stands on its base")
    # With the file's name back (the packing's shape keeps it), the reason says whether the .obj
    # convention (y) agrees.
    mesh.name = f"{name}.obj"
    chosen = choose_up(packing)
    assert chosen.name == STANDING[name]
    assert ("by convention too" if STANDING[name] == "y" else "but that way it has no base as broad") in chosen.reason


def z_up_bunny(folder):
    """The Stanford bunny turned so that its up (+y) is +z, saved as OBJ (a y-up format): a scan
    stored z-up, which the file convention alone would lay on its side."""
    import trimesh

    mesh = trimesh.load(MESHES / FILES["stanford-bunny"], force="mesh")
    x, y, z = mesh.vertices.T
    mesh.vertices = np.column_stack([x, -z, y])  # a rotation: y -> z, z -> -y
    path = Path(folder) / "bunny-zup.obj"
    mesh.export(path)
    return path


@pytest.mark.slow
def test_a_scan_stored_z_up_in_an_obj_file_stands_on_its_base(tmp_path, capsys):
    from ndpack.cli import main

    source = z_up_bunny(tmp_path)
    packing = pack_small(load(source))
    chosen = choose_up(packing)
    assert (chosen.axis, chosen.sign) == (2, 1), str(chosen)
    assert ".obj files are y-up by convention, but that way it has no base as broad" in chosen.reason
    # An asked-for axis overrides the base.
    assert choose_up(packing, "y") == nd.pictures.Up(1, 1, "asked for")
    # From its file, as `ndpack pack` writes it, the command line says the same.
    packing.params["source"] = str(source)
    saved = packing.save(tmp_path / "bunny.npz")
    assert main(["render", str(saved), "-o", str(tmp_path / "bunny.png"), "--size", "80x80"]) == 0
    assert "up:    z (it stands on its base" in capsys.readouterr().out
    assert main(["render", str(saved), "-o", str(tmp_path / "bunny.png"), "--size", "80x80", "--up", "y"]) == 0
    assert "up:    y (asked for)" in capsys.readouterr().out


def test_picture_says_which_way_is_up_and_why(tmp_path):
    # A flat block of spheres: it lies on its broad face, z up.
    corners = [[x, y, 0.0] for x in (0.0, 2.0) for y in (0.0, 1.0)]
    block = spheres(corners, [0.5] * 4, source="block.stl")
    shot = picture(block, tmp_path / "block.png", size=(60, 60))
    assert (shot.kind, shot.up.name) == ("render", "z")
    assert str(shot.up).startswith("z (it stands on its base: 100% of its footprint, the centre of mass above it")
    assert shot.up.reason.endswith(".stl files are z-up by convention")  # the convention picked among equals
    assert os.fspath(shot) == str(tmp_path / "block.png") and Path(shot).stat().st_size > 0
    # An asked-for axis is drawn and reported; a slice reports its up too; 2-D and fill plots have none.
    assert picture(block, tmp_path / "x.png", size=(60, 60), up="-x").up == nd.pictures.Up(0, -1, "asked for")
    assert picture(block, tmp_path / "block.svg").up.name == "z"
    flat = nd.pack(nd.Box([0, 0], [1, 1]), n=5, seed=0)
    assert picture(flat, tmp_path / "flat.png").up is None
    assert picture(flat, tmp_path / "fill.png", kind="fill").up is None


def test_bases_need_the_centre_of_mass_above_them():
    # A lever: a row of spheres x = 0..7 on a short foot x = 0..2 (two wide, along y). The foot is
    # broad enough (2/7 of the footprint) but the mass lies beyond it (mean x 2.8): it would tip
    # over. Upside down, on the long row, it stands.
    top = [[x, y, 1.0] for x in np.arange(8.0) for y in (0.0, 1.0)]
    foot = [[x, y, 0.0] for x in np.arange(3.0) for y in (0.0, 1.0)]
    found = {(base.axis, base.sign): base for base in bases(np.array(top + foot), np.full(22, 0.5))}
    assert (2, 1) not in found
    assert found[(2, -1)].fraction == pytest.approx(1.0)
    # Too few spheres, or spheres in a line, have no base: the convention or the extent decides.
    assert bases(np.zeros((3, 3)), np.ones(3)) == []
    assert bases(np.column_stack([np.arange(5.0), np.zeros(5), np.zeros(5)]), np.full(5, 0.5)) == []
