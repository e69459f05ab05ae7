"""The command line, through its real entry point."""

import subprocess
import sys

import ndpack as nd


def run(*args):
    return subprocess.run([sys.executable, "-m", "ndpack.cli", *args], capture_output=True, text=True, timeout=300)


def test_pack_a_builtin_shape_and_save(tmp_path):
    out = tmp_path / "box4.npz"
    result = run("pack", "box:dim=4", "-n", "30", "--grid", "6", "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert "spheres:  30" in result.stdout and "verified: valid" in result.stdout
    packing = nd.Packing.load(out)
    assert len(packing) == 30 and packing.dim == 4
    assert packing.verify(nd.Box([0] * 4, [1] * 4)).ok


def test_bad_shape_spec_gives_one_line_and_nonzero_exit():
    result = run("pack", "dodecahedron")
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "unknown shape 'dodecahedron'" in result.stderr
    result = run("pack", "box:dim")
    assert result.returncode == 2 and "key=value" in result.stderr


def test_impossible_parameters_and_backend():
    result = run("pack", "box", "-n", "0")
    assert result.returncode == 2 and "positive integer" in result.stderr
    result = run("pack", "box", "--backend", "abacus")
    assert result.returncode == 2 and "unknown backend" in result.stderr


def test_help_has_examples():
    result = run("pack", "--help")
    assert result.returncode == 0 and "examples:" in result.stdout and "box:dim=4" in result.stdout


def test_fast_mode_from_the_command_line(tmp_path):
    out = tmp_path / "square.npz"
    result = run("pack", "box:dim=2", "-n", "400", "--mode", "fast", "--backend", "numpy", "--grid", "20",
                 "-o", str(out), "-q")
    assert result.returncode == 0, result.stderr
    packing = nd.Packing.load(out)
    assert len(packing) == 400 and packing.params["mode"] == "fast"
    assert packing.verify(nd.Box([0, 0], [1, 1])).ok
    result = run("pack", "box", "--mode", "quick")
    assert result.returncode == 2 and "invalid choice" in result.stderr
