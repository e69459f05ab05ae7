"""Long coverings: Ctrl-C stops them within a second and keeps what they made, a protrusion that
calls for too many spheres is refused before any work, and the ball-union queries that made the
runs long are exact and interruptible.

The Ctrl-C tests run ``ndpack cover`` in a subprocess whose progress bar is forced on (its stderr
is made to look like a terminal), send SIGINT once the bar shows the step asked for, and time the
exit; the rest run in-process and take a few seconds.
"""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import ndpack as nd
from ndpack.geometry import ball_union
from ndpack.drivers.collision import covering, robots
from ndpack.cli import main
from ndpack.drivers.collision.estimate import TooManySpheres, estimate_count
from ndpack.io import load
from ndpack.samples import write as write_samples

#: Runs ``ndpack cover`` with stderr taken for a terminal (so that the progress bar shows).
TERMINAL = ("import sys\n"
            "class Terminal:\n"
            "    def __init__(self, stream): self.stream = stream\n"
            "    def isatty(self): return True\n"
            "    def __getattr__(self, name): return getattr(self.stream, name)\n"
            "sys.stderr = Terminal(sys.stderr)\n"
            "from ndpack.cli import console\n"
            "sys.exit(console())\n")


@pytest.fixture(scope="module")
def samples(tmp_path_factory):
    folder = tmp_path_factory.mktemp("samples")
    write_samples(folder)
    return folder


def interrupt(arguments, when: str, cwd):
    """Run ``ndpack cover ARGUMENTS``, send SIGINT once stderr shows ``when``; returns the exit
    status, stdout and stderr. (A run that never shows ``when`` ends by itself, and fails.)"""
    process = subprocess.Popen([sys.executable, "-c", TERMINAL, "cover", *arguments], cwd=cwd,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, env={**os.environ, "COLUMNS": "200"},
                               # Ctrl-C as a terminal delivers it: a test run started in the background
                               # (`cmd &` without job control) ignores SIGINT, and so would this child.
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    seen = b""
    os.set_blocking(process.stderr.fileno(), False)
    while when.encode() not in seen:
        assert process.poll() is None, f"ended before {when!r}: {seen.decode(errors='replace')[-2000:]}"
        chunk = process.stderr.read()
        seen += chunk or b""
        time.sleep(0.05)
    process.send_signal(signal.SIGINT)
    os.set_blocking(process.stderr.fileno(), True)
    out, err = process.communicate()
    return process.returncode, out.decode(), (seen + err).decode(errors="replace")


def test_ctrl_c_while_closing_gaps_keeps_the_covering_made(samples, tmp_path):
    out = tmp_path / "fan.npz"
    # 0.3% of the diagonal: about 4,000 spheres and some 15 s on 2 cores; the signal comes in the second set.
    code, printed, err = interrupt(
        [str(samples / "fandisk.obj"), "--protrusion", "0.003", "-o", str(out)], "set 2 of at most 12", tmp_path)
    assert code == 130, err[-2000:]  # stopped by the signal, in the set it came in (below), not at the end
    assert "stopped:  by Ctrl-C while closing gaps" in printed and "saved:" in printed
    assert "kept the spheres made so far" in err and "Traceback" not in err
    kept = load(out)
    assert kept.stop_reason == "interrupted" and len(kept) > 1000
    assert kept.params["covering"]["interrupted"].startswith("closing gaps")
    # Seen where it came: in the set under way then, or the next at the latest (not at the end).
    assert any(f"set {k} of at most 12" in kept.params["covering"]["interrupted"] for k in (2, 3)), \
        kept.params["covering"]["interrupted"]
    assert kept.params["covering"]["checks"] == 0  # stopped before the full check: reported on a quick one


def test_ctrl_c_before_the_first_cover_keeps_nothing(samples, tmp_path):
    out = tmp_path / "fan.npz"
    code, printed, err = interrupt(
        [str(samples / "fandisk.obj"), "--protrusion", "0.003", "-o", str(out)], "samples and candidates", tmp_path)
    assert code == 130, (code, err[-2000:])
    assert "ndpack: interrupted" in err and "Traceback" not in err
    assert not out.exists()


def test_an_interrupted_covering_says_so_and_saves_as_one():
    shape = nd.Box(np.zeros(3), np.ones(3))
    made = nd.cover(shape, n=4, samples=500, check_samples=500)
    made.params["interrupted"] = "closing gaps (fresh samples, set 2 of at most 12)"
    assert made.interrupted and made.summary().startswith("INTERRUPTED (Ctrl-C) while closing gaps")
    assert made.as_packing().stop_reason == "interrupted"
    made.params.pop("interrupted")
    assert not made.interrupted and made.as_packing().stop_reason == "covered"


# ------------------------------------------------------------------------------- too many spheres
def test_a_protrusion_calling_for_too_many_spheres_is_refused_before_any_work(samples, monkeypatch):
    mesh = nd.TriangleMesh.load(samples / "fandisk.obj")

    def no_work(*args, **kwargs):
        raise AssertionError("the covering started")

    monkeypatch.setattr(covering.Problem, "make", no_work)
    started = time.perf_counter()
    with pytest.raises(TooManySpheres) as refused:  # the case: 0.0005 on a part 7.6 across
        nd.cover(mesh, protrusion=0.0005)
    assert time.perf_counter() - started < 5.0
    error = refused.value
    assert error.reason == "samples" and error.limit == 20_000 and 2e5 < error.expected < 2e6
    message = str(error)
    assert f"calls for about {error.expected:,.0f} spheres" in message and "more than the 20,000 boundary" in message
    assert "give a larger protrusion" in message and "or a count n" in message and "samples of" in message
    # The protrusion it suggests is taken; more samples lift the first limit, then max_spheres is the one.
    assert estimate_count(mesh, error.suggested) <= error.suggested_count * 1.01
    with pytest.raises(TooManySpheres) as refused:
        nd.cover(mesh, protrusion=0.0001, samples=10**8)
    assert refused.value.reason == "max_spheres" and refused.value.expected > 1e6
    assert "more than the limit of 1,000,000: such a run takes hours" in str(refused.value)
    assert "max_spheres=None" in str(refused.value) or "raise max_spheres" in str(refused.value)


def test_the_command_line_refuses_in_its_own_options(samples, capsys):
    started = time.perf_counter()
    assert main(["cover", str(samples / "fandisk.obj"), "--protrusion-abs", "0.0005", "-q"]) == 2
    err = capsys.readouterr().err
    assert time.perf_counter() - started < 5.0
    assert err.count("\n") == 1 and err.startswith("ndpack: error: --protrusion-abs 0.0005 calls for about ")
    assert "(--protrusion-abs 0.0" in err and "a count (-n)" in err and "--samples" in err
    assert main(["cover", str(samples / "fandisk.obj"), "--protrusion", "0.00001", "--samples", "100000000"]) == 2
    err = capsys.readouterr().err
    assert "--protrusion 1e-05 calls for about" in err and "more than the limit of 1,000,000" in err
    assert "--max-spheres 0 lifts the limit" in err
    # A limit of one's own: named, without the hours a million would take.
    assert main(["cover", str(samples / "fandisk.obj"), "--protrusion", "0.01", "--max-spheres", "10", "-q"]) == 2
    err = capsys.readouterr().err
    assert "more than the limit of 10; give a larger protrusion" in err


def test_a_robot_is_refused_naming_the_link_before_any_work(samples, tmp_path, monkeypatch):
    monkeypatch.setattr(robots, "cover", lambda *args, **kwargs: pytest.fail("a link was covered"))
    with pytest.raises(TooManySpheres, match=r"link '\w+'"):
        robots.cover_urdf(samples / "arm.urdf", tmp_path / "out", protrusion_share=1e-6)
    assert not (tmp_path / "out").exists()


def test_the_estimate_is_near_the_count_made():
    square = nd.Box(np.zeros(2), np.ones(2))  # made 25 at 1% of the diagonal with 20,000 samples
    made = len(nd.cover(square, protrusion=0.01 * square.diagonal, samples=4000, check_samples=4000))
    assert made / 2 <= estimate_count(square, 0.01 * square.diagonal) <= made * 2
    ball = nd.Ball(np.zeros(3), 1.0)  # one sphere covers it, whatever the protrusion
    assert estimate_count(ball, 1e-5) <= 4


# ----------------------------------------------------------------------------- a robot's output
def test_a_robot_output_that_looks_like_a_file_is_refused(samples, tmp_path, capsys):
    assert main(["cover", str(samples / "arm.urdf"), "-n", "4", "-o", str(tmp_path / "arm.yml")]) == 2
    err = capsys.readouterr().err
    assert "arm.yml looks like a file name (it ends in .yml)" in err and "give a folder" in err
    assert "arm_spheres/" in err and not (tmp_path / "arm.yml").exists()
    # A folder so named is taken where it exists, or where the name ends with a separator.
    (tmp_path / "v1.2").mkdir()
    assert robots._out_dir(tmp_path / "v1.2") == tmp_path / "v1.2"
    assert robots._out_dir(f"{tmp_path}/arm.v2/") == tmp_path / "arm.v2"
    with pytest.raises(nd.errors.ParameterError, match="is a file"):
        (tmp_path / "f.txt").write_text("")
        robots._out_dir(tmp_path / "f.txt")


def test_an_interrupted_robot_writes_the_links_done(samples, tmp_path, monkeypatch):
    calls = []

    def cover_then_stop(*args, **kwargs):  # Ctrl-C in the second link's covering
        calls.append(args[0])
        if len(calls) == 2:
            raise KeyboardInterrupt
        return nd.cover(*args, **kwargs)

    monkeypatch.setattr(robots, "cover", cover_then_stop)
    result = robots.cover_urdf(samples / "arm.urdf", tmp_path / "out", n=4, samples=500, check_samples=500)
    assert len(result.links) == 1 and result.interrupted and not result.covered
    first = next(iter(result.links))
    report = (tmp_path / "out" / "report.json").read_text()
    assert f'"{result.interrupted[0]}"' in report and '"interrupted"' in report
    written = result.urdf.read_text()
    assert f"{first}_sphere_0" in written and f"{result.interrupted[0]}_sphere_0" not in written
    assert "INTERRUPTED (Ctrl-C) while covering" in result.summary()


# --------------------------------------------------------------------------------- the ball union
def all_pairs(points, centers, radii, clearances):
    """gap, covering, cheapest, cost and inside by every pair, in NumPy (the lowest index among equals)."""
    lengths = np.sqrt(((points[:, None, :] - centers[None, :, :]) ** 2).sum(axis=2))
    gaps, costs = lengths - radii, lengths - clearances
    covering = np.where(gaps <= 0, costs, np.inf)
    return (gaps.min(axis=1), np.where(np.isfinite(covering.min(axis=1)), covering.argmin(axis=1), -1),
            costs.argmin(axis=1), costs.min(axis=1),
            (((points[:, None, :] - centers[None, :, :]) ** 2).sum(axis=2) <= radii * radii).any(axis=1))


@pytest.mark.parametrize("dim", [2, 3, 5])
def test_ball_union_queries_equal_every_pair(dim):
    rng = np.random.default_rng(dim)
    for count in (1, 7, 300):
        centers = rng.random((count, dim))
        radii = np.exp(rng.normal(-2.5, 1.2, count))  # sizes over orders of magnitude, as in a covering
        if count > 2:
            centers[2], radii[2] = centers[0], radii[0]  # a tie: the lowest index wins
        clearances = radii * rng.random(count)
        points = np.vstack([rng.random((500, dim)) * 1.4 - 0.2, centers[:5]])
        expected = all_pairs(points, centers, radii, clearances)
        found = ball_union.best_balls(points, centers, radii, clearances)
        for want, got in zip(expected[:4], found):
            np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(ball_union.gaps(points, centers, radii), expected[0])
        np.testing.assert_array_equal(ball_union.covered(points, centers, radii), expected[4])
    empty = ball_union.best_balls(points, np.zeros((0, dim)), np.zeros(0), np.zeros(0))
    assert np.all(np.isinf(empty[0])) and np.all(empty[1] == -1) and not ball_union.covered(points, [], []).any()


def test_pieces_follow_the_time_taken():
    done, sizes = [], []
    for part in ball_union.pieces(5000, first=100, seconds=0.02):
        sizes.append(part.stop - part.start)
        done.append(np.arange(part.start, part.stop))
        time.sleep(1e-4 * sizes[-1])  # 0.1 ms a point: pieces of about 200
    assert np.array_equal(np.concatenate(done), np.arange(5000))
    assert sizes[0] == 100 and all(100 <= size <= 400 for size in sizes[1:-1])
