"""Compiling happens once per machine, never per shape.

- A new size of a shape, a new CSG tree of built-ins, a new mesh and a new tree around a known
  plug-in compile nothing, on numba, Warp (CPU) and numba-cuda (the CUDA simulator): their
  numbers go to the compiled interpreter of their dimension (a tape, ndpack.kernels.tape).
- A second process loads the compiled kernels from disk instead of compiling.
- A first compile says so, in one line, before it starts.
- Generated modules are named by their text, so a changed program never meets an old binary.
- The cache folder is trusted only when it and the files Python and Numba read there are the
  user's alone: otherwise one warning line, and this process compiles into a private folder.
  Folders are never repaired (chmod), planted files are never loaded.
"""

import hashlib
import json
import logging
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

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
    # (ndpack's own grids are said too, where this machine has not compiled them yet: see below.)
    notices = [line for line in said.splitlines() if line.startswith("ndpack: compiling") and "grid" not in line]
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


OWN_SCRIPT = """
import numpy as np
from ndpack.geometry import close_pairs, overlaps
rng = np.random.default_rng(0)
centers, radii = rng.random((300, 3)), np.full(300, 0.02)
print(len(close_pairs.grid(centers, radii, 1e-10, 1.0).pairs()[0]), len(overlaps.overlapping_pairs(centers, radii)[0]))
"""


def test_ndpacks_own_numba_grids_say_their_first_compile(tmp_path):
    """The conflict check's and the overlap check's Numba grids (ndpack's own functions, cached
    by Numba beside them or in NUMBA_CACHE_DIR) say their first compile, where it is kept and
    about how long it takes; a second process loads them and says nothing."""
    env = {**os.environ, "NDPACK_CACHE": str(tmp_path / "ndpack"), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    runs = [subprocess.run([sys.executable, "-c", OWN_SCRIPT], capture_output=True, text=True, timeout=600, env=env)
            for _ in range(2)]
    assert all(run.returncode == 0 for run in runs), runs[0].stderr[-3000:]
    assert runs[0].stdout == runs[1].stdout and int(runs[0].stdout.split()[0]) > 0  # the grids found pairs
    said = [line for line in runs[0].stderr.splitlines() if line.startswith("ndpack: compiling")]
    assert len(said) == 2, runs[0].stderr
    for line, what in zip(said, ("the conflict check's grid", "the overlap check's grid"), strict=True):
        assert f"numba kernels for {what} (first use on this machine, about " in line
        assert f"kept in {tmp_path / 'numba'} for next time" in line
    assert "compiling" not in runs[1].stderr
    # The next notice gives this machine's time for them: recorded under their names.
    recorded = json.loads((tmp_path / "ndpack" / "compile-times.json").read_text())
    assert {"numba: the conflict check's grid", "numba: the overlap check's grid"} <= set(recorded)


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


@pytest.fixture
def said():
    """The ndpack logger's warning lines while the test runs."""
    lines = []
    handler = logging.Handler(logging.WARNING)
    handler.emit = lambda record: lines.append(record.getMessage())
    logger = logging.getLogger("ndpack")
    logger.addHandler(handler)
    yield lines
    logger.removeHandler(handler)


def _mode(path):
    return path.stat().st_mode & 0o7777


def _give_away(path):
    """``path`` given to another user (nobody), which only root may do."""
    if os.geteuid() != 0:
        pytest.skip("making a file of another user needs root")
    os.chown(path, 65534, 65534)


def test_a_new_cache_folder_and_what_ndpack_writes_there_are_private(tmp_path, monkeypatch, said):
    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path / "new"))
    root = kernel_compile.cache_root()
    assert root == tmp_path / "new" and kernel_compile.cache_folder("numba") == root / "numba"
    for folder in (root, root / "numba", root / "numba" / "__pycache__", root / "warp"):
        assert _mode(folder) == 0o700, folder
    kernel_compile._record("numba", 12.5)
    module = kernel_compile._import_generated("X = 3\n", "numba")
    assert _mode(root / "compile-times.json") == 0o600 and _mode(root / "numba" / module.__file__) == 0o600
    assert kernel_compile._measured()["numba"] == 12.5 and not said


def test_the_cache_folder_follows_xdg_cache_home(tmp_path, monkeypatch):
    monkeypatch.delenv("NDPACK_CACHE", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert kernel_compile.cache_root() == tmp_path / "xdg" / "ndpack"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/cache")  # ignored, as the XDG specification asks
    assert kernel_compile.cache_root() == tmp_path / "home" / ".cache" / "ndpack"
    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path / "mine"))  # first
    assert kernel_compile.cache_root() == tmp_path / "mine"


def _fallback(said, refused, reason):
    """The one warning line names the refused folder, the reason and the folder used instead,
    which is this process's private temporary folder."""
    assert len(said) == 1, said
    scratch = kernel_compile._scratch[0]
    assert said[0].startswith(f"kernel cache {refused} refused: ") and reason in said[0], said
    assert f"compiling into {scratch} for this process only" in said[0]
    assert kernel_compile.cache_root() == scratch and _mode(scratch) == 0o700
    assert scratch.parent == Path(tempfile.gettempdir()) and os.access(scratch / "numba", os.W_OK)


def test_an_unwritable_cache_setting_warns_and_names_the_fallback(tmp_path, monkeypatch, said):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("NDPACK_CACHE", str(blocker))
    kernel_compile.cache_folder("numba")
    _fallback(said, blocker, f"{blocker} is not a folder")


@pytest.mark.parametrize("mode", [0o1777, 0o2775, 0o777], ids=["1777", "2775", "777"])
def test_a_cache_folder_others_may_write_keeps_its_mode_and_is_refused(tmp_path, monkeypatch, said, mode):
    # A root user pointing NDPACK_CACHE at /tmp must not change /tmp; nor a group's folder.
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(mode)
    monkeypatch.setenv("NDPACK_CACHE", str(shared))
    kernel_compile.cache_folder("numba")
    assert _mode(shared) == mode and not list(shared.iterdir())  # unchanged, and nothing made in it
    _fallback(said, shared, f"{shared} may be written by other users (mode {mode:o})")


def test_a_cache_folder_of_another_user_is_refused(tmp_path, monkeypatch, said):
    # Anyone can create /tmp/ndpack-cache first on a shared machine; modules are imported from it.
    theirs = tmp_path / "theirs"
    theirs.mkdir(mode=0o755)
    _give_away(theirs)
    monkeypatch.setenv("NDPACK_CACHE", str(theirs))
    kernel_compile.cache_folder("numba")
    _fallback(said, theirs, f"{theirs} belongs to another user (uid 65534)")


def test_a_cache_folder_under_one_anyone_may_replace_is_refused(tmp_path, monkeypatch, said):
    # /tmp is sticky (no one deletes or renames what is not theirs); a 0777 folder is not.
    (tmp_path / "open" / "cache").mkdir(parents=True)
    (tmp_path / "open").chmod(0o777)
    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path / "open" / "cache"))
    kernel_compile.cache_root()
    _fallback(said, tmp_path / "open" / "cache", f"{tmp_path / 'open'} above it may be written by anyone")


def test_group_writable_files_count_only_where_the_group_can_reach_them_and_links_never(tmp_path):
    # Under a umask of 002 Numba writes its files 0664: harmless in ndpack's 0700 folders.
    root = tmp_path / "cache"
    assert kernel_compile._open_cache(root) is None
    index = root / "numba" / "__pycache__" / "f.nbi"
    index.write_bytes(b"")
    index.chmod(0o664)
    assert kernel_compile._open_cache(root) is None
    for folder in (root, root / "numba", root / "numba" / "__pycache__"):
        folder.chmod(0o755)
    assert f"{index} may be written by other users (mode 664)" in kernel_compile._open_cache(root)
    index.chmod(0o644)
    assert kernel_compile._open_cache(root) is None
    os.link(index, tmp_path / "another-name")  # could be changed through a name elsewhere
    assert f"{index} has other names" in kernel_compile._open_cache(root)
    index.unlink()
    index.symlink_to(tmp_path / "another-name")  # leads to a file that is not checked here
    assert f"{index} is not a plain file or folder" in kernel_compile._open_cache(root)


#: Imports a generated module from the cache folder and calls a cached Numba function of it,
#: which reads the function's index (.nbi) in the cache folder's numba/__pycache__, if trusted.
PLANTED_SCRIPT = """
import sys
import numba
from ndpack.kernels import compile as kernel_compile

module = kernel_compile._import_generated(sys.argv[1], "numba")
function = numba.njit(cache=True)(module.f)
kernel_compile._checked_disk_caches({"f": function})
print(function(1))
"""
PLANTED_MODULE = "def f(x):\n    return x + 1\n"


class _Planted:
    """Unpickling it writes ``marker``: what a planted index would run."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return exec, (f"open({str(self.marker)!r}, 'w').write('ran')",)


@pytest.mark.parametrize("how", ["ours (control)", "another user's", "group-writable", "in an open __pycache__"])
def test_planted_numba_index_files_are_not_loaded(tmp_path, how):
    cache, marker = tmp_path / "cache", tmp_path / "marker"
    pycache = cache / "numba" / "__pycache__"
    pycache.mkdir(parents=True)
    for folder in (cache, cache / "numba", pycache):
        folder.chmod(0o755)  # the user's own folders, as `mkdir -p` makes them
    digest = hashlib.sha1(PLANTED_MODULE.encode()).hexdigest()[:20]
    index = pycache / f"ndpack_{digest}.f-1.py{sys.version_info[0]}{sys.version_info[1]}{sys.abiflags}.nbi"
    index.write_bytes(pickle.dumps(_Planted(marker)))
    index.chmod(0o644)
    if how == "another user's":
        _give_away(index)
    elif how == "group-writable":
        index.chmod(0o664)
    elif how == "in an open __pycache__":
        pycache.chmod(0o777)
    modes = {path: _mode(path) for path in (cache, pycache, index)}
    env = {key: value for key, value in os.environ.items() if key != "NUMBA_CACHE_DIR"}
    result = subprocess.run([sys.executable, "-c", PLANTED_SCRIPT, PLANTED_MODULE], capture_output=True, text=True,
                            timeout=300, env={**env, "NDPACK_CACHE": str(cache)})
    assert result.returncode == 0 and result.stdout.split() == ["2"], result.stderr[-3000:]
    warnings = [line for line in result.stderr.splitlines() if "refused" in line]
    if how == "ours (control)":  # the planted file would run where the cache is trusted
        assert marker.exists() and not warnings
        return
    assert not marker.exists(), "a planted index file was unpickled"
    assert len(warnings) == 1 and warnings[0].startswith(f"ndpack: kernel cache {cache} refused: "), result.stderr
    reason = {"another user's": f"{index} belongs to another user",
              "group-writable": f"{index} may be written by other users (mode 664)",
              "in an open __pycache__": f"{pycache} may be written by other users (mode 777)"}[how]
    assert reason in warnings[0] and "compiling into " in warnings[0] and "for this process only" in warnings[0]
    assert modes == {path: _mode(path) for path in (cache, pycache, index)}  # nothing repaired


def test_a_numba_cache_dir_others_may_write_is_not_read(tmp_path, monkeypatch, said):
    # NUMBA_CACHE_DIR sends Numba's files there instead of the checked __pycache__.
    import numba
    from numba.core import config

    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path / "cache"))
    for name, mode in (("private", 0o700), ("shared", 0o777)):
        folder = tmp_path / name
        folder.mkdir()
        folder.chmod(mode)
        monkeypatch.setattr(config, "CACHE_DIR", str(folder))
        module = kernel_compile._import_generated(f"def g_{name}(x):\n    return x * 2\n", "numba")
        function = numba.njit(cache=True)(getattr(module, f"g_{name}"))
        assert function._cache.cache_path.startswith(str(folder))
        kernel_compile._checked_disk_caches({"g": function})
        kept = function._cache.cache_path
        assert function(2) == 4
        if name == "private":
            assert kept.startswith(str(folder)) and not said
        else:
            assert kept is None and len(said) == 1 and said[0].startswith("Numba's disk cache ")
            assert f"{folder} may be written by other users (mode 777)" in said[0]


def test_a_notice_gives_the_last_compile_of_the_same_kernels(tmp_path, monkeypatch):
    """The estimate is the last time these kernels took on this machine, not the longest compile
    of their kind (other kernels, or older code: Warp's modules compiled 90 s at its default
    optimisation on an H100, 3 s at ndpack's); kernels never compiled here get the typical time."""
    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path))
    notices = []
    monkeypatch.setattr(kernel_compile, "notice", notices.append)
    kernel_compile._record("warp", 90.0)  # an older code's compile, recorded by kind only
    kernel_compile._record("warp", 3.2, "3-D shapes and meshes on cuda:0")
    kernel_compile.announce("warp", "3-D shapes and meshes on cuda:0", 5)
    kernel_compile.announce("warp", "2-D shapes on cuda:0", 5)
    assert "about 3 s" in notices[0] and "about 5 s" in notices[1], notices
    assert kernel_compile._measured()["warp"] == 90.0  # the longest stays recorded
    kernel_compile._record("warp", 2.4, "3-D shapes and meshes on cuda:0")
    kernel_compile.announce("warp", "3-D shapes and meshes on cuda:0")
    assert "about 2 s" in notices[2], notices


def test_warp_modules_compile_at_ndpacks_optimisation_level():
    """The generated Warp module sets its optimisation level (Warp's default took 30x as long to
    compile on an H100 for no faster packing: kernel_compile.WARP_OPTIMIZATION)."""
    pytest.importorskip("warp")
    import ndpack as nd
    from ndpack.kernels.compiled import compiled_program

    program = compiled_program(nd.Ball(np.zeros(3), 1.0)).program
    module = kernel_compile.warp_module(program, "float64", "")
    assert f"'optimization_level': {kernel_compile.WARP_OPTIMIZATION}" in Path(module.__file__).read_text()


def test_a_numba_cuda_kernels_first_launch_is_timed_for_the_next_notice(tmp_path, monkeypatch):
    """numba-cuda compiles a kernel at its first launch (it has no compile event): where Numba's
    disk cache holds nothing of it, that launch is announced once per title and timed, the
    kernels' times adding up to the next notice's estimate for the title; later launches and a
    cached kernel are left alone."""
    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path))
    notices, launched = [], []
    monkeypatch.setattr(kernel_compile, "notice", notices.append)
    monkeypatch.setattr(kernel_compile, "_announced_cuda", set())
    monkeypatch.setattr(kernel_compile, "_cuda_seconds", {})
    monkeypatch.setitem(kernel_compile._titles, "fake_cuda_module", "fake kernels")

    def py_func():
        pass

    py_func.__module__ = "fake_cuda_module"

    class Fake:  # what CudaKernel reads of a numba-cuda kernel
        def __init__(self, index_path):
            self.py_func = py_func
            self._cache = SimpleNamespace(_cache_file=SimpleNamespace(_index_path=str(index_path)))

        def __getitem__(self, config):
            return lambda *args: launched.append((config, args))

    cached_index = tmp_path / "cached.nbi"
    cached_index.write_text("")
    fresh = [kernel_compile.CudaKernel(Fake(tmp_path / f"missing{k}.nbi")) for k in range(2)]
    cached = kernel_compile.CudaKernel(Fake(cached_index))
    for kernel in (*fresh, cached, *fresh):
        kernel[1, 32](7)
    assert len(launched) == 5 and len(notices) == 1 and "numba-cuda kernels for fake kernels" in notices[0]
    recorded = kernel_compile._measured()
    assert "numba-cuda: fake kernels" in recorded and kernel_compile._cuda_seconds.keys() == {"fake kernels"}
    # The next notice for the title gives what was recorded for it (set here: no timing is asserted).
    estimate = 41.6
    kernel_compile._record("numba-cuda", estimate, "fake kernels")
    monkeypatch.setattr(kernel_compile, "_announced_cuda", set())
    kernel_compile.CudaKernel(Fake(tmp_path / "missing2.nbi"))[1, 32](8)
    assert f"about {estimate:.0f} s" in notices[-1], notices


class _SmallProgram:
    """What warp_module reads of a program: a title, a dimension and its Warp source."""

    dim = 2

    def __init__(self, title):
        self.title = title

    def source(self, dialect, float_name):
        return "@wp.func\ndef sd(p: VecD, prm: wp.array(dtype=F)):\n    return wp.length(p) - prm[0]\n"


_SMALL_KERNELS = '''
@wp.kernel
def distances(points: wp.array(dtype=VecD), prm: wp.array(dtype=F), out: wp.array(dtype=F)):
    i = wp.tid()
    out[i] = sd(points[i], prm)
'''


def test_a_warp_module_in_warps_cache_is_known_as_built(tmp_path, monkeypatch):
    """The compile notice asks whether Warp's cache holds the module's binary: not before it is
    built, yes after (on a CPU too, where Warp names the folder for blocks of 1 thread: every
    cached module had been announced as compiling)."""
    wp = pytest.importorskip("warp")
    if not wp.is_cpu_available():
        pytest.skip("Warp's CPU compiler is not installed here (the GPU machine's copy)")
    import uuid

    monkeypatch.setenv("NDPACK_CACHE", str(tmp_path))
    program = _SmallProgram(f"a stand-in program {uuid.uuid4().hex}")  # a module no cache holds yet
    module = kernel_compile.warp_module(program, "float64", _SMALL_KERNELS)
    assert not kernel_compile._warp_cached(wp, module, "cpu")
    notices = []
    monkeypatch.setattr(kernel_compile, "notice", notices.append)
    loaded = kernel_compile.warp_module(program, "float64", _SMALL_KERNELS, device="cpu")
    assert loaded is module and len(notices) == 1  # built, and said so
    assert kernel_compile._warp_cached(wp, module, "cpu")
    out = wp.empty(2, dtype=module.F, device="cpu")
    wp.launch(module.distances, dim=2, device="cpu", inputs=[
        wp.array([[3.0, 4.0], [0.0, 0.5]], dtype=module.VecD, device="cpu"),
        wp.array([1.0], dtype=module.F, device="cpu"), out])
    np.testing.assert_allclose(out.numpy(), [4.0, -0.5])
