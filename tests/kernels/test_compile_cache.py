"""Compiling happens once per machine, never per shape.

- A new size of a shape, a new CSG tree of built-ins, a new mesh and a new tree around a known
  plug-in compile nothing, on numba, Warp (CPU) and numba-cuda (the CUDA simulator): their
  numbers go to the compiled interpreter of their dimension (a tape, ndpack.kernels.tape).
- A second process loads the compiled kernels from disk instead of compiling.
- A first compile says so, in one line, before it starts.
- Generated modules are named by their text, so a changed program never meets an old binary.
"""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from ndpack.kernels import compile as kernel_compile

#: Packs shapes on one backend; after a first use of each kind (a CSG part, a mesh, a plug-in),
#: counts what the new sizes, tree, mesh and plug-in tape compile.
SCRIPT = """
import json, math, sys
import numpy as np
import trimesh
import ndpack as nd
from ndpack.kernels import compile as kernel_compile

backend, device = sys.argv[1], sys.argv[2] if sys.argv[2] != "-" else None
light = len(sys.argv) > 3


def part(side):
    return nd.Box([0.0, 0.0, 0.0], [side] * 3) - nd.Ball([side] * 3, 0.6 * side)


def shell(p, params):
    r = math.sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])
    return max(r - params[0], params[1] - r)


def plugin(outer, inner):
    return nd.ScalarFunction(shell, 3, [[-1.0] * 3, [1.0] * 3], params=[outer, inner])


def run(shape):
    if light:  # the CUDA simulator runs kernels in Python: the kernels' set-up and one clearance
        points = np.stack([shape.bounds.mean(axis=0)] * 3)
        clearance = nd.backends.get_backend(backend).clearance(shape, points, np.zeros((0, 3)), np.zeros(0),
                                                                np.zeros((3, 0), dtype=np.int64))
        np.testing.assert_allclose(clearance, -shape.distance(points), rtol=0, atol=1e-12)
        return
    packing = nd.pack(shape, 4, grid=5, backend=backend, device=device)
    assert len(packing) == 4 and packing.verify().ok, packing


def counts():
    return {"compiles": dict(kernel_compile.COMPILES), "modules": dict(kernel_compile.MODULES)}


run(part(1.0))
run(nd.TriangleMesh.from_trimesh(trimesh.creation.icosphere(subdivisions=1)))
run(plugin(0.8, 0.3))
first = counts()
run(part(2.7))
run(part(0.001))
run((nd.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]) | nd.Capsule([0.0, 0.0, 0.0], [1.5, 1.5, 0.0], 0.3))
    - nd.Cylinder([0.5, 0.5, -1.0], [0.5, 0.5, 2.0], 0.2))
run(nd.TriangleMesh.from_trimesh(trimesh.creation.capsule(height=1.0, radius=0.4)))
run(plugin(0.9, 0.5).translate([0.3, 0.0, 0.0]) - nd.Ball([0.3, 0.0, 0.6], 0.3))
print(json.dumps({"first": first, "then": counts()}))
"""


def _pack_new_shapes(folder, backend, device="-", **env):
    script = folder / "new_shapes.py"  # a file: a plug-in's source must be readable
    script.write_text(SCRIPT)
    light = ["light"] if env.get("NUMBA_ENABLE_CUDASIM") else []
    result = subprocess.run(
        [sys.executable, str(script), backend, device, *light], capture_output=True, text=True, timeout=900,
        env={**os.environ, **env},
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout.strip().splitlines()[-1])


def _backend(name: str, device: str):
    """The backend ``name`` on ``device``, or None where it cannot run here."""
    from ndpack import backends

    try:
        return backends.get_backend(name, device=device)
    except Exception:  # noqa: BLE001 - not installed, no driver or device, no compiler for it
        return None


def _gpu(name: str) -> bool:
    """Whether ``name`` runs on a real GPU here (the GPU machine; never in CI)."""
    if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1":
        return False
    backend = _backend(name, "cuda:0")
    return backend is not None and (name != "warp" or backend.device.is_cuda)


@pytest.mark.parametrize("backend, device, env", [
    ("numba", "-", {}),
    ("warp", "cpu", {}),
    ("numba-cuda", "-", {"NUMBA_ENABLE_CUDASIM": "1"}),
    ("warp", "cuda:0", {}),
    ("numba-cuda", "cuda:0", {}),
], ids=["numba", "warp-cpu", "numba-cuda-simulator", "warp-cuda", "numba-cuda-gpu"])
def test_new_sizes_trees_meshes_and_plugin_tapes_compile_nothing(tmp_path, backend, device, env):
    if backend == "warp":
        pytest.importorskip("warp")
    if device == "cuda:0" and not _gpu(backend):
        pytest.skip("no CUDA GPU here")
    if device == "cpu" and _backend(backend, device) is None:
        pytest.skip("Warp's CPU compiler is not installed here (the GPU machine's copy)")
    counts = _pack_new_shapes(tmp_path, backend, device, **env)
    # The first uses made modules (loaded from disk or compiled, as this machine's cache has it);
    # after them, nothing new: no module, no compile.
    assert counts["first"]["modules"], counts
    assert counts["then"] == counts["first"], counts


#: Packs a small shape on numba, then prints what the entry kernels' dispatchers did.
CACHE_SCRIPT = """
import json, sys
import numpy as np
import ndpack as nd
from ndpack.kernels import compile as kernel_compile

shape = nd.Box([0.0, 0.0], [float(sys.argv[1])] * 2) - nd.Ball([0.0, 0.0], 0.3)
packing = nd.pack(shape, 40, grid=12, backend="numba")
namespace, _, _ = nd.backends.get_backend("numba")._kernels(shape)
entries = [namespace[name] for name in ("converge_all", "index_query")]
print(json.dumps({
    "hits": sum(sum(entry.stats.cache_hits.values()) for entry in entries),
    "misses": sum(sum(entry.stats.cache_misses.values()) for entry in entries),
    "compiles": kernel_compile.COMPILES.get("numba", 0),
    "file": entries[0].py_func.__code__.co_filename,
    "radii": packing.radii.tolist(),
    "valid": bool(packing.verify().ok),
}))
"""


def _run(cache, size=1.0):
    result = subprocess.run(
        [sys.executable, "-c", CACHE_SCRIPT, str(size)], capture_output=True, text=True, timeout=600,
        env={**os.environ, "NDPACK_CACHE": str(cache), "NDPACK_BACKEND": "numba"},
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout.strip().splitlines()[-1]), result.stderr


def test_a_second_process_loads_the_kernels_from_disk_and_a_first_says_it_compiles(tmp_path):
    (first, said), (second, quiet) = _run(tmp_path), _run(tmp_path)
    # Compiled, and saved (the shape-free kernels by a second process, which this one then loads).
    assert first["misses"] > 0 and first["compiles"] > 0
    assert second["hits"] > 0 and second["misses"] == 0 and second["compiles"] == 0  # loaded
    assert first["file"] == second["file"] and first["file"].startswith(str(tmp_path))
    assert first["valid"] and second["valid"]
    np.testing.assert_array_equal(first["radii"], second["radii"])
    # One line before the compile, naming what and where; none when loading.
    notices = [line for line in said.splitlines() if line.startswith("ndpack: compiling")]
    assert len(notices) == 1 and "numba kernels for 2-D shapes" in notices[0] and str(tmp_path) in notices[0]
    assert "compiling" not in quiet
    # Another size is other numbers for the same code: loaded, not compiled.
    other, _ = _run(tmp_path, size=2.0)
    assert other["file"] == first["file"] and other["misses"] == 0 and other["compiles"] == 0
    assert other["valid"]
    # What the cache holds, as `ndpack backends` lists it.
    os.environ["NDPACK_CACHE"], previous = str(tmp_path), os.environ.get("NDPACK_CACHE")
    try:
        listed = kernel_compile.cached_modules()
    finally:
        if previous is None:
            del os.environ["NDPACK_CACHE"]
        else:
            os.environ["NDPACK_CACHE"] = previous
    assert any(entry["what"] == "2-D shapes, CPU" and entry["compiled"] for entry in listed), listed


def test_generated_modules_are_named_by_their_text(tmp_path, monkeypatch):
    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path))
    one = kernel_compile._import_generated("X = 1\n", "numba")
    again = kernel_compile._import_generated("X = 1\n", "numba")
    other = kernel_compile._import_generated("X = 2\n", "numba")
    assert one.__file__ == again.__file__ != other.__file__
    assert (one.X, other.X) == (1, 2)
    modified = os.stat(one.__file__).st_mtime_ns
    kernel_compile._import_generated("X = 1\n", "numba")  # an equal file is not rewritten
    assert os.stat(one.__file__).st_mtime_ns == modified


def test_an_unwritable_cache_setting_falls_back_to_the_temporary_folder(tmp_path, monkeypatch):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("NDPACK_CACHE", str(blocker))
    monkeypatch.setattr(kernel_compile.tempfile, "gettempdir", lambda: str(tmp_path / "tmp"))
    folder = kernel_compile.cache_folder("numba")
    assert folder == tmp_path / "tmp" / "ndpack-cache" / "numba" and os.access(folder, os.W_OK)


def test_a_cache_folder_of_another_user_is_refused(tmp_path, monkeypatch):
    # Anyone can create /tmp/ndpack-cache first on a shared machine; modules are imported from it.
    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(kernel_compile.tempfile, "gettempdir", lambda: str(tmp_path / "tmp"))
    (tmp_path / "cache" / "numba").mkdir(parents=True)
    (tmp_path / "tmp" / "ndpack-cache" / "numba").mkdir(parents=True)
    someone_else = os.getuid() + 1
    monkeypatch.setattr(kernel_compile.os, "getuid", lambda: someone_else)
    with pytest.raises(OSError, match="belongs to another user.*NDPACK_CACHE"):
        kernel_compile.cache_folder("numba")


def test_a_cache_folder_is_private(tmp_path, monkeypatch):
    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path / "new"))
    folder = kernel_compile.cache_folder("numba")
    assert folder.stat().st_mode & 0o777 == 0o700 and folder.parent.stat().st_mode & 0o077 == 0
    shared = tmp_path / "shared"
    (shared / "numba").mkdir(parents=True)
    shared.chmod(0o777)
    monkeypatch.setenv("NDPACK_CACHE", str(shared))
    kernel_compile.cache_folder("numba")
    assert shared.stat().st_mode & 0o022 == 0  # ours, so others lose the right to write
