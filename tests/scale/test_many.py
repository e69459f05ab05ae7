"""Many parts at once (issue 25): ``pack_many`` on a process pool, on Dask, and ``ndpack pack A B -o out/``.

Each part must come out exactly as ``nd.pack`` makes it alone (same seed, same backend: NumPy, which
the pool's and the cluster's workers inherit from the environment). Small counts and a coarse grid
keep the file near half a minute on 2 cores; most of it is starting worker processes.
"""

import json
import re

import numpy as np
import pytest

import ndpack as nd
from ndpack.cli import main
from ndpack.io.shape_sources import load_shape

QUICK = dict(grid=8, seed=3)


def _box_mesh(path, size=1.0):
    """A small closed mesh file (12 triangles)."""
    import trimesh

    trimesh.creation.box(extents=[size, 0.6 * size, 0.4 * size]).export(path)
    return path


def _alone(source, n):
    """The part packed alone, as the reference."""
    return nd.pack(load_shape(source) if isinstance(source, str) else source, n=n, progress=False, **QUICK)


def _assert_same(packing, reference):
    np.testing.assert_array_equal(packing.centers, reference.centers)
    np.testing.assert_array_equal(packing.radii, reference.radii)


def test_a_dozen_parts_on_a_pool_equal_packing_them_one_by_one(tmp_path):
    import ndpack.samples

    (fandisk,) = ndpack.samples.write(tmp_path, names=["fandisk"], robot=False)
    (tmp_path / "other").mkdir()
    stl = _box_mesh(tmp_path / "other" / "fandisk.stl")  # the same stem: named fandisk-2
    sources = [str(fandisk), str(stl), "box:dim=2", "box:dim=3", "annulus:dim=2", "torus", "box:dim=3",
               nd.Box([0, 0], [2, 1]), nd.Box([0, 0, 0], [1, 1, 1]) - nd.Ball([1, 1, 1], 0.6),
               nd.Ball([0, 0], 1.0) - nd.Ball([0.3, 0], 0.4), "simplex:dim=3", nd.Ball([0, 0, 0], 1.0)]
    result = nd.pack_many(sources, n=30, workers=2, progress=False, **QUICK)
    assert result.ok and not result.failed and result.out is None, result.summary()
    names = [part["name"] for part in result.parts]
    assert names[:7] == ["fandisk", "fandisk-2", "box_dim_2", "box_dim_3", "annulus_dim_2", "torus", "box_dim_3-2"]
    assert names[7:9] == ["part7", "part8"] and len(result.packings) == 12
    for name, source in zip(names, sources):
        _assert_same(result.packings[name], _alone(source, 30))
    assert result.packings["part7"].shape is sources[7]  # an object part keeps the caller's shape
    assert result.packings["fandisk"].params["source"] == str(fandisk.resolve())
    assert result.summary().splitlines()[-1].startswith("total: 12 parts: 12 done")


def test_parts_on_a_dask_cluster_equal_packing_them_one_by_one(tmp_path):
    distributed = pytest.importorskip("distributed")
    mesh = _box_mesh(tmp_path / "block.obj")
    sources = [str(mesh), "annulus:dim=2", nd.Box([0, 0, 0], [1, 2, 1]) - nd.Ball([0, 0, 0], 0.5), str(mesh)]
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    with cluster, distributed.Client(cluster) as client:
        result = nd.pack_many(sources, n=30, client=client, out=tmp_path / "out", progress=False, **QUICK)
    assert result.ok, result.summary()
    assert [part["name"] for part in result.parts] == ["block", "annulus_dim_2", "part2", "block-2"]
    for name, source in zip(result.packings, sources):
        _assert_same(result.packings[name], _alone(source, 30))  # loaded from out/<name>.npz


def test_a_broken_part_is_reported_the_rest_written_and_a_rerun_packs_only_what_is_missing(tmp_path):
    broken = tmp_path / "broken.obj"
    broken.write_text("this is not\na mesh at all\n")
    mesh = _box_mesh(tmp_path / "block.stl")
    out = tmp_path / "out"
    sources = ["box:dim=2", str(broken), str(mesh), "annulus:dim=2"]
    first = nd.pack_many(sources, n=20, out=out, workers=2, progress=False, **QUICK)
    assert not first.ok and [part["name"] for part in first.failed] == ["broken"]
    assert "no triangles" in first.failed[0]["error"] and "\n" not in first.failed[0]["error"]
    assert sorted(path.name for path in out.iterdir()) == ["annulus_dim_2.npz", "block.npz", "box_dim_2.npz",
                                                           "manifest.json"]
    manifest = json.loads((out / "manifest.json").read_text())
    assert [part["status"] for part in manifest["parts"]] == ["done", "failed", "done", "done"]
    assert manifest["parts"][0]["params"] == {"n": 20, **QUICK} and manifest["parts"][2]["spheres"] == 20
    assert manifest["parts"][1]["error"] == first.failed[0]["error"]
    assert re.search(r"^broken +failed +the mesh file .* has no triangles", first.summary(), re.M)

    # Again, one output deleted: only it (and the broken part) are tried; the others are kept as they are.
    kept = {name: (out / f"{name}.npz").stat().st_mtime_ns for name in ("box_dim_2", "annulus_dim_2")}
    (out / "block.npz").unlink()
    again = nd.pack_many(sources, n=20, out=out, workers=1, progress=False, **QUICK)
    assert [part["status"] for part in again.parts] == ["skipped", "failed", "done", "skipped"]
    assert kept == {name: (out / f"{name}.npz").stat().st_mtime_ns for name in kept}
    _assert_same(again.packings["box_dim_2"], _alone("box:dim=2", 20))  # skipped parts load from their files
    _assert_same(again.packings["block"], _alone(str(mesh), 20))
    assert [part["status"] for part in json.loads((out / "manifest.json").read_text())["parts"]] == \
        ["skipped", "failed", "done", "skipped"]

    # Other parameters are another packing: everything is packed again.
    other = nd.pack_many(sources[:1], n=10, out=out, workers=1, progress=False, **QUICK)
    assert other.parts[0]["status"] == "done" and len(other.packings["box_dim_2"]) == 10


def test_bad_arguments_are_refused_before_any_work(tmp_path):
    with pytest.raises(nd.ParameterError, match="unknown format 'npy'"):
        nd.pack_many(["box"], format="npy")
    with pytest.raises(nd.ParameterError, match="progress"):
        nd.pack_many(["box"], progress=False, on_round=print)
    (tmp_path / "file").write_text("")
    with pytest.raises(nd.ParameterError, match="is a file"):
        nd.pack_many(["box"], out=tmp_path / "file")
    mesh = _box_mesh(tmp_path / "block.obj")
    with pytest.raises(nd.ParameterError, match="would overwrite its source"):
        nd.pack_many([str(mesh)], out=tmp_path, format="mesh")


def test_the_command_line_packs_several_shapes_and_a_folder_into_a_folder(tmp_path, capsys):
    parts = tmp_path / "parts"
    parts.mkdir()
    a, b = _box_mesh(parts / "a.obj"), _box_mesh(parts / "b.stl", 2.0)
    (parts / "notes.txt").write_text("not a mesh")
    out = tmp_path / "out"
    assert main(["pack", str(a), str(b), "-n", "20", "--grid", "8", "-o", str(out) + "/", "-q"]) == 0
    printed = capsys.readouterr().out
    assert sorted(path.name for path in out.iterdir()) == ["a.npz", "b.npz", "manifest.json"]
    assert re.search(r"^a +done +20 spheres", printed, re.M) and "total: 2 parts: 2 done" in printed
    assert len(nd.Packing.load(out / "b.npz")) == 20

    # A folder stands for its mesh files (notes.txt is not one); all made already, so skipped.
    assert main(["pack", str(parts), "-n", "20", "--grid", "8", "-o", str(out), "--workers", "1", "-q"]) == 0
    assert "total: 2 parts: 2 skipped" in capsys.readouterr().out

    # A quoted pattern, and a failed part: exit 1, the other part written.
    (parts / "c.ply").write_text("ply\nbroken\n")
    assert main(["pack", str(parts / "*.*"), "-n", "20", "--grid", "8", "-o", str(out), "--workers", "1"]) == 1
    assert re.search(r"^c +failed +", capsys.readouterr().out, re.M) and (out / "a.npz").exists()

    # Several shapes and one output file: refused, in one line, before any work.
    assert main(["pack", str(a), str(b), "-n", "20", "-o", str(tmp_path / "both.npz")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "give -o a folder ending in / (e.g. -o out/)" in error
    assert not (tmp_path / "both.npz").exists()
