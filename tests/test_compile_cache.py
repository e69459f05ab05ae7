"""Compiled Numba kernels are kept on disk: a second process loads them instead of compiling,
and gets the same packing; a changed program never meets an old binary."""

import json
import os
import subprocess
import sys

import numpy as np

from ndpack.kernels import compile as kernel_compile

#: Packs a small shape on numba, then prints what the entry kernels' dispatchers did.
SCRIPT = """
import json, sys
import numpy as np
import ndpack as nd

shape = nd.Box([0.0, 0.0], [float(sys.argv[1])] * 2) - nd.Ball([0.0, 0.0], 0.3)
packing = nd.pack(shape, 40, grid=12, backend="numba")
namespace, _ = nd.backends.get_backend("numba")._kernels(shape)
entries = [namespace[name] for name in ("converge_all", "clearance_all")]
print(json.dumps({
    "hits": sum(sum(entry.stats.cache_hits.values()) for entry in entries),
    "misses": sum(sum(entry.stats.cache_misses.values()) for entry in entries),
    "file": entries[0].py_func.__code__.co_filename,
    "radii": packing.radii.tolist(),
    "valid": bool(packing.verify().ok),
}))
"""


def _run(cache, size=1.0):
    result = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(size)], capture_output=True, text=True, timeout=600,
        env={**os.environ, "NDPACK_CACHE": str(cache), "NDPACK_BACKEND": "numba"},
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_a_second_process_loads_the_kernels_from_disk(tmp_path):
    first, second = _run(tmp_path), _run(tmp_path)
    assert first["misses"] > 0 and first["hits"] == 0  # compiled, and saved
    assert second["hits"] > 0 and second["misses"] == 0  # loaded, nothing compiled
    assert first["file"] == second["file"] and first["file"].startswith(str(tmp_path))
    assert first["valid"] and second["valid"]
    np.testing.assert_array_equal(first["radii"], second["radii"])
    # Another size changes a compile-time constant (the finite-difference step): a new module,
    # compiled afresh, not the first one's binary.
    other = _run(tmp_path, size=2.0)
    assert other["file"] != first["file"] and other["misses"] > 0 and other["hits"] == 0
    assert other["valid"]


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
