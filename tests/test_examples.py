"""Every script in examples/ runs at a small size, and docs/api.md matches the docstrings.

Each example runs in a subprocess, as a user would run it, on the NumPy backend (no compile of
the packing kernels; meshes and scalar plug-ins still compile their Numba distance), writing into
a folder it is given with ``--out`` and that does not exist yet: every example takes ``--out
FOLDER`` the same way, makes the folder and writes its files inside, nothing beside it. The whole
file takes about a minute on 2 cores.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
SMALL_ARMADILLO = ROOT / "tests" / "data" / "meshes" / "armadillo-20k.ply"

#: name -> (arguments, with {out} for the output folder; files it must write there)
RUNS = {
    "apollonian_square.py": (
        ["-n", "300", "--out", "{out}"],
        ["square.png", "square.svg", "square_gap.png", "square_fill.png", "square.npz"],
    ),
    "armadillo.py": (
        ["--mesh", str(SMALL_ARMADILLO), "-n", "150", "--grid", "12", "--size", "160", "--out", "{out}"],
        ["armadillo.png", "armadillo_cut.png", "armadillo.npz", "armadillo.vtp", "armadillo.glb",
         "armadillo.sph", "armadillo_curobo.json"],
    ),
    "ball_4d.py": (
        ["-n", "150", "--out", "{out}"],
        ["ball4d_slices.png", "ball4d_slice.svg", "ball4d_3d.png", "ball4d.npz"],
    ),
    "custom_plugin.py": (
        ["-n", "100", "--out", "{out}"],
        ["cross.png", "cross_numpy.npz", "cross_scalar.npz"],
    ),
    "fill_vs_count.py": (
        ["--n2", "300", "--n3", "300", "--out", "{out}"],
        ["fill_vs_count.png"],
    ),
    "gyroid_5d.py": (["-n", "20", "--out", "{out}"], ["gyroid_numpy.npz"]),
    "manifold_part.py": (["-n", "40", "--out", "{out}"], ["manifold_part.png"]),
}


def test_every_example_is_run_here():
    scripts = {path.name for path in EXAMPLES.glob("*.py")}
    assert scripts == set(RUNS), f"add the new examples to RUNS in {Path(__file__).name}: {sorted(scripts ^ set(RUNS))}"


def test_every_example_takes_an_output_folder():
    for name, (arguments, _) in RUNS.items():
        assert arguments[arguments.index("--out") + 1] == "{out}", f"{name}: --out names the folder, nothing in it"
        assert "--out" in (EXAMPLES / name).read_text(), name


@pytest.mark.parametrize("name", sorted(RUNS))
def test_example_runs_small(name, tmp_path):
    arguments, outputs = RUNS[name]
    out = tmp_path / "results"  # not there yet: the example makes it
    command = [sys.executable, str(EXAMPLES / name), *(a.format(out=out) for a in arguments), "--backend", "numpy"]
    # The checkout's ndpack, whatever the folder it runs in finds first.
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=tmp_path, env=env)
    assert result.returncode == 0, f"{name} failed:\n{result.stdout}\n{result.stderr}"
    missing = [file for file in outputs if not (out / file).is_file() or (out / file).stat().st_size == 0]
    assert not missing, f"{name} did not write {missing} into --out; it printed:\n{result.stdout}"
    beside = sorted(path.name for path in tmp_path.iterdir() if path != out)
    assert not beside, f"{name} wrote {beside} beside the --out folder, not in it"
    assert "valid: False" not in result.stdout


def test_api_reference_is_up_to_date(tmp_path):
    fresh = tmp_path / "api.md"
    result = subprocess.run([sys.executable, str(ROOT / "docs" / "make_api.py"), "-o", str(fresh)],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    current = ROOT / "docs" / "api.md"
    assert current.exists() and current.read_text() == fresh.read_text(), (
        "docs/api.md is out of date with the docstrings: run `python docs/make_api.py` and keep the result"
    )
