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
    assert "spheres:  30 (the count asked for)" in result.stdout and "verified: valid" in result.stdout
    assert f"saved:    {out}" in result.stdout and "s in all" in result.stdout
    packing = nd.Packing.load(out)
    assert len(packing) == 30 and packing.dim == 4
    assert packing.verify(nd.Box([0] * 4, [1] * 4)).ok
    # Without -o nothing is written, and the summary says so.
    unsaved = run("pack", "box:dim=2", "-n", "5", "--grid", "6")
    assert unsaved.returncode == 0 and "saved:    nothing (give -o PATH" in unsaved.stdout


def test_one_sphere_has_no_pair_and_says_so_not_minus_infinity():
    report = nd.pack(nd.Ball([0, 0, 0], 1.0), n=1).verify()
    assert report.ok and "-inf" not in report.summary() and "none, no pair" in report.summary()


def test_bad_shape_spec_gives_one_line_and_nonzero_exit():
    result = run("pack", "dodecahedron")
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "unknown shape 'dodecahedron'" in result.stderr
    result = run("pack", "box:dim")
    assert result.returncode == 2 and "key=value" in result.stderr
    # A parameter the shape does not take: named, with the ones it does take.
    from ndpack.io.named_shapes import from_spec

    with pytest.raises(nd.NdpackError, match=r"does not take size; it takes dim=3"):
        from_spec("box:dim=3,size=2")


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


# ------------------------------------------------------------------ shape sources, formats, subcommands
import os  # noqa: E402
import signal  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

MESHES = Path(__file__).parent / "data" / "meshes"


#: The command line with the greedy driver's run state made to stop the process at once: a command
#: that reaches a packing says so on stderr (``NO_PACKING``) instead of packing.
NO_PACKING = "ndpack test: a packing was started"
GUARDED = (
    "import sys\n"
    "from ndpack.drivers.greedy import protosphere\n"
    "def refuse(*args, **kwargs):\n"
    f"    raise SystemExit({NO_PACKING!r})\n"
    "protosphere.RunState.__init__ = refuse\n"
    "from ndpack.cli import console\n"
    "sys.argv[0] = 'ndpack'\n"
    "sys.exit(console())\n"
)


def run_without_packing(*args):
    """``run(*args)`` where any packing would end the process (see ``NO_PACKING``)."""
    return subprocess.run([sys.executable, "-c", GUARDED, *args], capture_output=True, text=True, timeout=300)


def one_line_error(result, *words):
    assert result.returncode == 2, (result.stdout, result.stderr)
    line = result.stderr.strip().splitlines()[-1]
    assert line.startswith("ndpack: error:") and "Traceback" not in result.stderr, result.stderr
    for word in words:
        assert word in line, line
    return line


@pytest.fixture(scope="module")
def saved_square(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "square.npz"
    result = run("pack", "square", "-n", "60", "--backend", "numpy", "--grid", "16", "-o", str(out), "-q")
    assert result.returncode == 0, result.stderr
    return out


def test_pack_a_mesh_file_and_verify_it_from_the_recorded_source(tmp_path):
    mesh = next(MESHES.glob("cow*.ply"))
    out = tmp_path / "cow.json"
    result = run("pack", str(mesh), "-n", "25", "--backend", "numpy", "--grid", "12", "-o", str(out), "-q")
    assert result.returncode == 0, result.stderr
    packing = nd.Packing.load(out)
    assert len(packing) == 25 and packing.params["source"] == str(mesh.resolve())
    result = run("verify", str(out))
    assert result.returncode == 0 and "valid" in result.stdout, result.stderr


def test_pack_a_script_and_a_plugin(tmp_path):
    script = tmp_path / "part.py"
    script.write_text("import ndpack as nd\nshape = nd.Box([0, 0], [2, 1]) - nd.Ball([1, 0.5], 0.3)\n")
    out = tmp_path / "part.csv"
    result = run("pack", str(script), "-n", "20", "--backend", "numpy", "--grid", "16", "-o", str(out), "-q")
    assert result.returncode == 0, result.stderr
    assert nd.Packing.load(out).centers[:, 0].max() > 1.0  # the 2x1 box, not a unit square
    (tmp_path / "my_plugin_shapes.py").write_text(
        "import ndpack as nd\ndef slab():\n    return nd.Box([0, 0, 0], [1, 1, 0.25])\n")
    out = tmp_path / "slab.npz"
    result = subprocess.run([sys.executable, "-m", "ndpack.cli", "pack", "my_plugin_shapes:slab", "-n", "10",
                             "--backend", "numpy", "--grid", "8", "-o", str(out), "-q"],
                            capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    packing = nd.Packing.load(out)
    assert np.all(packing.radii <= 0.125 + 1e-9)
    # A recorded module is code: verify runs it only when told to, and only where it imports.
    verify_here = [sys.executable, "-m", "ndpack.cli", "verify", str(out)]
    one_line_error(subprocess.run(verify_here, capture_output=True, text=True, timeout=300, cwd=tmp_path),
                   "module 'my_plugin_shapes'", "--trust-source")
    one_line_error(run("verify", str(out), "--trust-source"), "no module")  # not beside the file
    result = subprocess.run([*verify_here, "--trust-source"], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    result = subprocess.run([*verify_here, "--shape", "my_plugin_shapes:slab"], capture_output=True, text=True,
                            timeout=300, cwd=tmp_path)
    assert result.returncode == 0, result.stderr


def test_bad_sources_and_outputs_give_one_line(tmp_path):
    one_line_error(run("pack", str(tmp_path / "missing.stl")), "no such file")
    one_line_error(run("pack", str(tmp_path)), "folder")
    broken = tmp_path / "broken.py"
    broken.write_text("raise RuntimeError('no part today')\n")
    one_line_error(run("pack", str(broken)), "no part today")
    empty = tmp_path / "empty.py"
    empty.write_text("x = 1\n")
    one_line_error(run("pack", str(empty)), "does not set `shape`")
    one_line_error(run("pack", "no_such_module_xyz:shape"), "no_such_module_xyz")
    one_line_error(run("pack", "box", "-o", str(tmp_path / "out.xyz")), "unknown suffix '.xyz'")
    one_line_error(run("pack", "box", "-o", str(tmp_path / "none" / "out.npz")), "no folder")
    one_line_error(run("pack", "box", "--backend", "abacus"), "unknown backend")


def test_outputs_a_format_cannot_hold_are_refused_before_packing(tmp_path):
    for args, words in (
            (("pack", "square", "-n", "100000", "-o", str(tmp_path / "sq.stl")), "3-D spheres, not a 2-D"),
            (("pack", "box:dim=4", "-n", "100000", "-o", str(tmp_path / "b.ply")), "not a 4-D packing"),
            (("pack", "box", "-n", "100000", "-o", str(tmp_path / "b.ply"), "--format", "curobo"), "must end in .json"),
            (("pack", "box", "-n", "100000", "-o", str(tmp_path / "b.vtp"), "--option", "colour=red"),
             "no option colour"),
            (("pack", "box", "-n", "100000", "--format", "csv"), "-o PATH")):
        result = run_without_packing(*args)
        assert NO_PACKING not in result.stderr, args  # refused before any packing started
        one_line_error(result, words)
    assert not list(tmp_path.iterdir())


def test_format_options_and_a_failed_save_keeps_the_packing(tmp_path):
    coarse, fine = tmp_path / "coarse.obj", tmp_path / "fine.obj"
    for out, options in ((coarse, []), (fine, ["--option", "subdivisions=2"])):
        result = run("pack", "box", "-n", "5", "--backend", "numpy", "--grid", "8", "-o", str(out), "-q", *options)
        assert result.returncode == 0, result.stderr
    assert len(nd.Packing.load(fine)) == len(nd.Packing.load(coarse)) == 5
    assert fine.stat().st_size > 3 * coarse.stat().st_size  # four times the triangles a sphere
    out = tmp_path / "bad.vtp"
    line = one_line_error(run("pack", "box", "-n", "5", "--backend", "numpy", "--grid", "8", "-o", str(out), "-q",
                              "--option", "encoding=utf8"), "encoding must be", "kept in")
    kept = nd.Packing.load(str(out) + ".npz")
    assert len(kept) == 5 and kept.verify(nd.Box([0] * 3, [1] * 3)).ok, line


def test_verify_fails_on_a_violation_and_needs_a_shape(saved_square, tmp_path):
    packing = nd.Packing.load(saved_square)
    bad = packing.replace_spheres(packing.centers.copy(), packing.radii * 1.5, packing.rounds)
    bad.save(tmp_path / "bad.npz")
    result = run("verify", str(tmp_path / "bad.npz"))
    assert result.returncode == 1 and "overlapping" in result.stdout
    bare = tmp_path / "bare.npz"  # spheres made elsewhere: no recorded source
    nd.Packing(packing.centers, packing.radii, packing.rounds, volume=1.0).save(bare)
    one_line_error(run("verify", str(bare)), "--shape")
    assert run("verify", str(bare), "--shape", "square").returncode == 0
    one_line_error(run("verify", str(tmp_path / "missing.npz")), "no such")


def test_render_and_info(saved_square, tmp_path):
    for name in ("square.png", "square.svg"):
        result = run("render", str(saved_square), "-o", str(tmp_path / name))
        assert result.returncode == 0, result.stderr
        assert (tmp_path / name).stat().st_size > 1000
    result = run("render", str(saved_square), "-o", str(tmp_path / "fill.png"), "--kind", "fill")
    assert result.returncode == 0 and (tmp_path / "fill.png").exists(), result.stderr
    one_line_error(run("render", str(saved_square), "-o", str(tmp_path / "x.gif")), ".png")
    result = run("info", str(saved_square))
    assert result.returncode == 0, result.stderr
    assert "60 in 2-D" in result.stdout and "median" in result.stdout and "source: square" in result.stdout
    assert "repaired:   no" in result.stdout
    one_line_error(run("info", str(tmp_path / "nothing.npz")), "no such")
    # `ndpack info x.npz | head -1`: the reader leaves early; no traceback.
    reader_gone = subprocess.Popen([sys.executable, "-m", "ndpack.cli", "info", str(saved_square)],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    reader_gone.stdout.close()
    assert reader_gone.wait(timeout=300) == 141 and b"Traceback" not in reader_gone.stderr.read()


def test_render_a_3d_packing(tmp_path):
    out = tmp_path / "ball.npz"
    assert run("pack", "ball", "-n", "20", "--backend", "numpy", "--grid", "8", "-o", str(out), "-q").returncode == 0
    result = run("render", str(out), "-o", str(tmp_path / "ball.png"), "--size", "120x100", "--view", "-10,-20",
                 "--clip", "0,0,0,-1,0,0")  # negative numbers need no '='
    assert result.returncode == 0, result.stderr
    import matplotlib.image

    assert matplotlib.image.imread(tmp_path / "ball.png").shape[:2] == (100, 120)
    one_line_error(run("render", str(out), "--clip", "0,0,1"), "--clip needs 6")
    one_line_error(run("render", str(out), "--kind", "fill", "--view", "10,20"), "--view", "fill plot")


def test_backends_lists_every_backend_with_a_reason():
    result = run("backends")
    assert result.returncode == 0, result.stderr
    table, cache = result.stdout.strip().split("\n\n")
    lines = table.splitlines()
    assert [line.split()[0] for line in lines] == nd.backends.names()
    assert lines[0].split()[1] == "ok"  # numpy always works
    assert cache.startswith("compiled kernels are kept in ") and " MB)" in cache


def test_every_subcommand_has_help_with_examples():
    for command in ("pack", "verify", "render", "info"):
        result = run(command, "--help")
        assert result.returncode == 0 and "examples:" in result.stdout, command
    assert "backends" in run("--help").stdout


@pytest.mark.skipif(os.name != "posix", reason="sends SIGINT")
def test_ctrl_c_keeps_what_was_packed(tmp_path):
    out = tmp_path / "stopped.npz"
    process = subprocess.Popen([sys.executable, "-m", "ndpack.cli", "pack", "box:dim=2", "-n", "100000",
                                "--backend", "numpy", "--grid", "40", "-o", str(out), "-q"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               # Ctrl-C as a terminal delivers it: a job started in the background
                               # (`cmd &` without job control) ignores SIGINT, and so do its children.
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(8)  # imports, prototypes, then a few rounds
    process.send_signal(signal.SIGINT)
    try:
        stdout, stderr = process.communicate(timeout=120)
    finally:
        process.kill()  # never leave a packing running after a failed test
    assert process.returncode == 130, stderr
    packing = nd.Packing.load(out)
    assert 0 < len(packing) < 100000 and packing.stop_reason == "interrupted"
    assert packing.verify(nd.Box([0, 0], [1, 1])).ok


def test_a_repaired_packing_says_so_in_its_files_and_in_info(saved_square, tmp_path):
    # A packing the final check repaired is not the greedy packing it claims to be: the record
    # travels with it (npz and json) and `ndpack info` shows it.
    packing = nd.Packing.load(saved_square)
    record = {"outside": 2, "overlapping_pairs": 1, "shrunk": 3, "dropped": 0, "worst_poke_out": 0.01,
              "worst_overlap": float("-inf"), "cause": "a test"}
    packing.repair = record
    for name in ("repaired.npz", "repaired.json"):
        loaded = nd.Packing.load(packing.save(tmp_path / name))
        assert loaded.repair == {**record, "worst_overlap": None}
        result = run("info", str(tmp_path / name))
        assert result.returncode == 0, result.stderr
        assert "repaired:   3 sphere(s) shrunk and 0 dropped" in result.stdout and "a test" in result.stdout


def test_a_packing_file_never_runs_the_code_it_names(saved_square, tmp_path):
    """A packing someone sent you may record a script or a module as its shape: verify,
    render and info must run neither (each would leave a marker file)."""
    script = tmp_path / "elsewhere" / "payload.py"
    script.parent.mkdir()
    script.write_text(f"open({str(tmp_path / 'script-ran')!r}, 'w').close()\nimport ndpack as nd\n"
                      f"shape = nd.Box([0, 0], [1, 1])\n")
    (tmp_path / "payload_module.py").write_text(
        f"open({str(tmp_path / 'module-ran')!r}, 'w').close()\nimport ndpack as nd\n"
        f"shape = nd.Box([0, 0], [1, 1])\n")
    square = nd.Packing.load(saved_square)
    for source, marker, words in ((str(script), "script-ran", "Python script"),
                                  ("payload_module:shape", "module-ran", "module 'payload_module'")):
        crafted = tmp_path / f"crafted-{marker}.npz"
        square.params["source"] = source
        square.save(crafted)

        def here(*args):
            return subprocess.run([sys.executable, "-m", "ndpack.cli", *args], capture_output=True, text=True,
                                  timeout=300, cwd=tmp_path)

        one_line_error(here("verify", str(crafted)), words, "--shape")
        result = here("render", str(crafted), "-o", str(tmp_path / "picture.svg"))
        assert result.returncode == 0 and "without the outline" in result.stderr, result.stderr
        assert here("info", str(crafted)).returncode == 0
        assert not (tmp_path / marker).exists(), f"{source} ran"
        assert here("verify", str(crafted), "--trust-source").returncode == 0  # asked for: it runs
        assert (tmp_path / marker).exists()


UNWRITABLE = next((folder for folder in ("/proc", "/sys") if os.path.isdir(folder)), None)


@pytest.mark.skipif(UNWRITABLE is None, reason="no read-only folder to write into")
def test_outputs_that_cannot_be_written_are_refused_before_any_work(saved_square):
    result = run_without_packing("pack", "square", "-n", "50000", "-o", f"{UNWRITABLE}/x.npz")
    assert NO_PACKING not in result.stderr  # refused before any packing started
    one_line_error(result, "cannot write")
    assert result.stdout == ""
    one_line_error(run("render", str(saved_square), "-o", f"{UNWRITABLE}/x.png"), "cannot write")


def test_a_save_that_fails_late_keeps_the_packing(tmp_path, monkeypatch, capsys):
    """A disk that fills up after the check: the packing goes beside the output instead."""
    import errno

    from ndpack import cli, io as ndio

    wanted = tmp_path / "square.csv"
    save = ndio.save

    def full_disk(packing, path, *args, **kwargs):
        if str(path) == str(wanted):
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return save(packing, path, *args, **kwargs)

    monkeypatch.setattr(ndio, "save", full_disk)
    assert cli.main(["pack", "square", "-n", "20", "--backend", "numpy", "--grid", "8", "-q", "-o", str(wanted)]) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert "No space left" in line and f"kept in {wanted}.npz" in line, line
    assert len(nd.Packing.load(f"{wanted}.npz")) == 20


def test_numeric_options_and_unreadable_files_give_one_line(saved_square, tmp_path):
    for tol in ("-1", "nan", "inf", "x"):
        result = run("verify", str(saved_square), "--tol", tol)
        assert result.returncode == 2 and ">= 0" in result.stderr and "Traceback" not in result.stderr
    for command, option, value, words in (("pack", "--seed", "-1", ">= 0"), ("render", "--size", "0x0", "pixels"),
                                          ("render", "--at", "nan,0.5", "finite")):
        target = ["square"] if command == "pack" else [str(saved_square), "-o", str(tmp_path / "x.svg")]
        result = run(command, *target, option, value)
        assert result.returncode == 2 and words in result.stderr and "Traceback" not in result.stderr, result.stderr
    with pytest.raises(nd.NdpackError, match="seed must be"):
        nd.pack(nd.Box([0, 0], [1, 1]), 3, seed=-1)
    noise = tmp_path / "noise.npz"
    noise.write_bytes(np.random.default_rng(0).bytes(2000))
    line = one_line_error(run("info", str(noise)), "never loads")
    assert "allow_pickle" not in line and "pickle.load" not in line


def test_an_open_mesh_file_is_capped_or_refused(tmp_path, capsys):
    import trimesh

    from ndpack.cli import main

    def error_line(*argv):  # in process: five subprocesses would cost 10 s
        assert main(list(argv)) == 2
        return capsys.readouterr().err.strip()

    box = trimesh.creation.box()
    path = tmp_path / "open.stl"
    trimesh.Trimesh(box.vertices, box.faces[box.face_normals[:, 0] < 0.9], process=False).export(path)
    assert error_line("pack", str(path), "--holes", "refuse").startswith("ndpack: error: the mesh is open: 1 hole")
    out = tmp_path / "open.npz"
    assert main(["pack", str(path), "--holes", "cap", "-n", "10", "--grid", "8", "-o", str(out), "-q"]) == 0
    assert nd.Packing.load(out).params["holes"] == "cap"
    capsys.readouterr()
    # Saved and loaded again (another format): still the recorded choice.
    again = nd.Packing.load(out).save(tmp_path / "again.json")
    with warnings.catch_warnings():
        warnings.simplefilter("error", nd.MeshWarning)  # the recorded holes="cap": no default, no warning
        for saved in (out, again):
            assert main(["verify", str(saved), "--independent"]) == 0
            assert "independent check: 0 spheres with points outside" in capsys.readouterr().out
        assert main(["render", str(again), "--kind", "slice", "-o", str(tmp_path / "slice.svg")]) == 0
        assert main(["info", str(again)]) == 0
        assert "holes:      cap (an open mesh's holes closed by caps" in capsys.readouterr().out
    # The command line overrides it: --holes, or a --shape of its own.
    assert "the mesh is open: 1 hole" in error_line("verify", str(out), "--holes", "refuse")
    assert "--holes applies to a mesh file" in error_line("verify", str(out), "--shape", "box", "--holes", "cap")
    with pytest.warns(nd.MeshWarning, match="open .1 hole"):  # --shape: the file's own default, cap
        assert main(["verify", str(out), "--shape", str(path)]) == 0
    # A file is data: a recorded choice ndpack does not know is refused in one line.
    crafted = nd.Packing.load(out)
    crafted.params["holes"] = "leak"
    assert "records holes='leak', which is none of cap, refuse" in error_line(
        "verify", str(crafted.save(tmp_path / "crafted.npz")))
    # A mesh packed without --holes: capped by default, and recorded so.
    with pytest.warns(nd.MeshWarning, match="open .1 hole"):
        assert main(["pack", str(path), "-n", "5", "--grid", "8", "-o", str(tmp_path / "default.npz"), "-q"]) == 0
    assert nd.Packing.load(tmp_path / "default.npz").params["holes"] == "cap"


def test_warnings_are_one_line_without_paths_and_name_cli_options(tmp_path):
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=2)
    sphere.update_faces(np.flatnonzero(sphere.triangles_center[:, 2] < 0.85))  # a hole at the top
    sphere.remove_unreferenced_vertices()
    sphere.export(tmp_path / "open.obj")
    result = run("pack", str(tmp_path / "open.obj"), "-n", "5", "--mode", "fast", "--grid", "8")
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert lines and all(line.startswith("ndpack: warning: ") for line in lines)
    assert "--holes cap" in result.stderr and "holes='cap'" not in result.stderr and ".py:" not in result.stderr


def test_sign_option_is_recorded_and_a_crossing_mesh_says_how_inside_is_told(tmp_path):
    import trimesh

    first, second = trimesh.creation.box(extents=[1, 1, 1]), trimesh.creation.box(extents=[1, 1, 1])
    second.apply_translation([0.5, 0.3, 0.2])
    trimesh.util.concatenate([first, second]).export(tmp_path / "crossing.obj")  # two boxes through each other
    result = run("pack", str(tmp_path / "crossing.obj"), "-n", "5", "--mode", "fast", "--grid", "8")
    assert result.returncode == 0, result.stderr
    assert "note:" in result.stdout and "crosses itself" in result.stdout and "winding number" in result.stdout
    out = tmp_path / "forced.npz"
    result = run("pack", str(tmp_path / "crossing.obj"), "-n", "5", "--mode", "fast", "--grid", "8",
                 "--sign", "winding", "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert nd.Packing.load(out).params["sign"] == "winding"
    assert run("verify", str(out)).returncode == 0
    refused = run("pack", "box:dim=3", "-n", "3", "--sign", "winding")
    assert refused.returncode == 2 and "--sign applies to a mesh file" in refused.stderr


def test_samples_writes_the_files_the_docs_use_and_a_missing_one_says_how_to_get_it(tmp_path, capsys):
    from ndpack.cli import main

    assert main(["samples", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert all(name in printed for name in ("cow.obj", "fandisk.obj", "armadillo.obj", "arm.urdf"))
    cow = nd.TriangleMesh.load(tmp_path / "cow.obj")
    assert cow.dim == 3 and "5804 triangles" in repr(cow)
    assert "<robot name=\"arm\">" in (tmp_path / "arm.urdf").read_text()
    assert main(["samples", str(tmp_path), "--suffix", ".stl"]) == 0 and (tmp_path / "fandisk.stl").exists()
    assert main(["samples", str(tmp_path / "new" / "parts")]) == 0 and (tmp_path / "new" / "parts" / "cow.obj").exists()
    assert main(["samples", str(tmp_path / "cow.obj")]) == 2
    assert main(["samples", str(tmp_path), "--suffix", "stl"]) == 2
    assert "--suffix is a file suffix" in capsys.readouterr().err
    assert main(["pack", str(tmp_path / "nowhere" / "cow.obj")]) == 2
    assert "`ndpack samples` writes cow.obj" in capsys.readouterr().err


def test_a_shape_one_sphere_fills_says_so_and_what_to_try(capsys):
    from ndpack.cli import main

    assert main(["pack", "ball:dim=4", "-n", "50", "--grid", "6"]) == 0
    printed = capsys.readouterr().out
    assert "spheres:  1 (no room left)" in printed and "annulus:dim=4" in printed
    assert main(["pack", "annulus:dim=4", "-n", "20", "--grid", "6"]) == 0
    assert "one sphere fills" not in capsys.readouterr().out


def test_dim_given_twice_must_agree():
    # box:dim=3 --dim 4 once packed a 4-D box labelled box:dim=3.
    result = run("pack", "box:dim=3", "--dim", "4", "-n", "3")
    assert result.returncode == 2 and "box:dim=3 says dim=3 and --dim says 4" in result.stderr
    same = run("pack", "box:dim=3", "--dim", "3", "-n", "3", "--grid", "4", "-q")
    assert same.returncode == 0 and "shape:    box:dim=3 -> Box(lower=[0.0, 0.0, 0.0]" in same.stdout
    # --dim alone: the line names the shape packed, not the word typed.
    added = run("pack", "box", "--dim", "4", "-n", "3", "--grid", "4", "-q")
    assert added.returncode == 0 and "shape:    box:dim=4 -> Box(lower=[0.0, 0.0, 0.0, 0.0]" in added.stdout


def test_a_dense_bed_and_a_size_distribution_from_the_command_line(tmp_path):
    out = tmp_path / "bed.npz"
    dense = run("pack", "box:dim=3", "--periodic", "all", "--sizes", "radius:0.1", "--dense", "-n", "150", "-q",
                "-o", str(out))
    assert dense.returncode == 0, dense.stderr
    assert "spheres:  150 (jammed: the densest random bed found)" in dense.stdout
    assert "contacts:" in dense.stdout and "dense mode" in dense.stdout
    bed = nd.Packing.load(out)
    assert len(bed) == 150 and bed.fill > 0.55 and np.ptp(bed.radii) == 0
    sized = run("pack", "box:dim=2", "--sizes", "discrete:radii=0.04/0.02,shares=0.5/0.5,by=mass",
                "--solid-fraction", "0.3", "-q")
    assert sized.returncode == 0, sized.stderr
    assert "sized mode" in sized.stdout and "verified: valid" in sized.stdout


def test_size_options_that_do_not_fit_say_what_was_wrong():
    for args, words in ((("--sizes", "lognormal:median=0.05"), "lognormal:median=M,sigma=S"),
                        (("--sizes", "radius:0.1", "--solid-fraction", "2"), "share of the volume")):
        result = run_without_packing("pack", "box:dim=3", *args)  # argparse's own usage and error lines
        assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr
        assert "error: argument" in result.stderr and words in result.stderr, result.stderr
    one_line_error(run_without_packing("pack", "box:dim=3", "--dense"), "need --sizes")
    one_line_error(run_without_packing("pack", "box:dim=3", "--sizes", "radius:0.1", "--tiles", "2"),
                   "--tiles does not go with --sizes")
