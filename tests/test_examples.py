"""Every script in examples/ runs at a small size, and docs/api.md matches the docstrings.

Each example runs in a subprocess, as a user would run it, on the NumPy backend (no compile of
the packing kernels; meshes and scalar plug-ins still compile their Numba distance), writing into
a temporary folder. The whole file takes about a minute on 2 cores.
"""

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
    "gyroid_5d.py": (["-n", "20"], []),  # prints only
    "manifold_part.py": (["-n", "40", "--out", "{out}/part.png"], ["part.png"]),
}


def test_every_example_is_run_here():
    scripts = {path.name for path in EXAMPLES.glob("*.py")}
    assert scripts == set(RUNS), f"add the new examples to RUNS in {Path(__file__).name}: {sorted(scripts ^ set(RUNS))}"


@pytest.mark.parametrize("name", sorted(RUNS))
def test_example_runs_small(name, tmp_path):
    arguments, outputs = RUNS[name]
    command = [sys.executable, str(EXAMPLES / name), *(a.format(out=tmp_path) for a in arguments), "--backend", "numpy"]
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert result.returncode == 0, f"{name} failed:\n{result.stdout}\n{result.stderr}"
    missing = [file for file in outputs if not (tmp_path / file).is_file() or (tmp_path / file).stat().st_size == 0]
    assert not missing, f"{name} did not write {missing}; it printed:\n{result.stdout}"
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
