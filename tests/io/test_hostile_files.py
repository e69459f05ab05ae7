"""Hostile files cost nothing (issue 45): each is refused in one line with exit status 2, in under
a second and under a memory ceiling, by ``ndpack info``, ``verify`` and ``render``.

Every file is made here, in a temporary folder. Each case runs in one child process that calls the
command line's own entry point (:func:`ndpack.cli.console`) once per command, with its address
space capped by ``RLIMIT_AS``. The cap is the peak address space of the same child reading a good
packing (info, verify and render, on the NumPy backend: NumPy, SciPy, Matplotlib and ndpack
imported), measured first in this module, plus 200 MiB: address space runs far above resident
memory (shared libraries, thread stacks, numba's LLVM where it loads), so a fixed figure would be
wrong on another machine. A file that made ndpack allocate what it declares (16 GB for the npz
header, 2 GB for the zip bomb, gigabytes for the YAML aliases) fails there with a MemoryError,
which the child prints as a traceback. The modules are imported before the clock starts, so each
command's time is the file's.
"""

from __future__ import annotations

import json
import os
import resource
import struct
import subprocess
import sys
import zipfile
import zlib
from io import BytesIO
from pathlib import Path

import numpy as np
import pytest

import ndpack as nd
from ndpack.io import limits
from ndpack.io.metadata import metadata

#: Above the footprint of a normal run: what a hostile file may cost at most.
HEADROOM = 200 << 20

#: Each command's time with the modules already imported.
SECONDS = 1.0

#: One child: run each command line given (a JSON list of argument lists) through the CLI's entry
#: point; print each one's exit status, output and time, and the peak address space (VmPeak).
CHILD = r"""
import contextlib, io, json, sys, time, traceback
import matplotlib.pyplot, ndpack.cli, ndpack.io, ndpack.pictures, ndpack.io.shape_sources, ndpack.verify
results = []
for argv in json.loads(sys.argv[1]):
    out, err = io.StringIO(), io.StringIO()
    start = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        sys.argv = ["ndpack", *argv]
        try:
            code = ndpack.cli.console()
        except BaseException:
            traceback.print_exc()
            code = None
    results.append({"code": code, "stdout": out.getvalue(), "stderr": err.getvalue(),
                    "seconds": time.perf_counter() - start})
status = open("/proc/self/status").read()
peak = int(next(line.split()[1] for line in status.splitlines() if line.startswith("VmPeak:"))) * 1024
print(json.dumps({"results": results, "peak": peak}))
"""


def run_child(commands: list[list[str]], ceiling: int | None = None) -> dict:
    """Run ``commands`` in one child, its address space capped at ``ceiling`` bytes."""

    def cap():
        if ceiling is not None:
            resource.setrlimit(resource.RLIMIT_AS, (ceiling, ceiling))

    result = subprocess.run([sys.executable, "-c", CHILD, json.dumps(commands)], capture_output=True, text=True,
                            timeout=120, preexec_fn=cap, env={**os.environ, "NDPACK_BACKEND": "numpy"})
    assert result.returncode == 0 and result.stdout.strip(), f"the child failed: {result.stderr[-3000:]}"
    return json.loads(result.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("hostile")


@pytest.fixture(scope="module")
def square(folder) -> nd.Packing:
    return nd.pack(nd.Box([0, 0], [1, 1]), n=10, grid=8, backend="numpy")


@pytest.fixture(scope="module")
def ceiling(folder, square) -> int:
    """The footprint of reading a good packing (info, verify, render), plus :data:`HEADROOM`."""
    if not Path("/proc/self/status").exists():
        pytest.skip("needs /proc/self/status to measure the footprint")
    good = square.save(folder / "good.npz")
    report = run_child([["info", str(good)], ["verify", str(good), "--shape", "box:dim=2"],
                        ["render", str(good), "-o", str(folder / "good.png")]])
    assert [result["code"] for result in report["results"]] == [0, 0, 0], report
    return report["peak"] + HEADROOM


# ------------------------------------------------------------------------------ the files
def _npy(array) -> bytes:
    buffer = BytesIO()
    np.lib.format.write_array(buffer, np.asanyarray(array), allow_pickle=False)
    return buffer.getvalue()


def _members(packing: nd.Packing) -> dict[str, bytes]:
    """The ``.npy`` members of ``packing``'s ``.npz``, as ndpack writes them."""
    arrays = dict(metadata=np.array(json.dumps(metadata(packing))), centers=packing.centers, radii=packing.radii,
                  rounds=packing.rounds, stats_time=packing.stats.time, stats_count=packing.stats.count,
                  stats_fill=packing.stats.fill, medial_axis=np.zeros((0, packing.dim)), medial_radii=np.zeros(0))
    return {f"{name}.npy": _npy(value) for name, value in arrays.items()}


def _zip(path: Path, members: dict[str, bytes]) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return path


def npz_header(folder: Path, square: nd.Packing) -> Path:
    """258 kB whose ``centers.npy`` header declares (10**9, 2): 16 GB."""
    members = _members(square)
    header = BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (10**9, 2)})
    members["centers.npy"] = header.getvalue() + np.random.default_rng(0).bytes(256_000)
    return _zip(folder / "header.npz", members)


def _deflated_zeros(prefix: bytes, zeros: int) -> tuple[bytes, int]:
    """A raw deflate stream of ``prefix`` and ``zeros`` zero bytes, and its CRC, without compressing
    them all: after a full flush the compressor starts afresh, so each MiB of zeros compresses to
    the same bytes."""
    block = 1 << 20
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    head = compressor.compress(prefix) + compressor.flush(zlib.Z_FULL_FLUSH)
    one = compressor.compress(bytes(block)) + compressor.flush(zlib.Z_FULL_FLUSH)
    assert compressor.compress(bytes(block)) + compressor.flush(zlib.Z_FULL_FLUSH) == one
    whole, rest = divmod(zeros, block)
    tail = compressor.compress(bytes(rest)) + compressor.flush()
    crc, zero_block = zlib.crc32(prefix), bytes(block)
    for _ in range(whole):
        crc = zlib.crc32(zero_block, crc)
    return head + one * whole + tail, zlib.crc32(bytes(rest), crc)


def zip_bomb(folder: Path, square: nd.Packing) -> Path:
    """2 MB whose arrays inflate to 2 GB of zeros: (62,500,000, 2) centres, as many radii and rounds.
    Written by hand: zipfile would deflate the 2 GB itself."""
    count = 62_500_000
    entries = {}
    for name, data in _members(square).items():
        compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
        entries[name] = (compressor.compress(data) + compressor.flush(), zlib.crc32(data), len(data))
    for name, dtype, shape in (("centers", "<f8", (count, 2)), ("radii", "<f8", (count,)), ("rounds", "<i8", (count,))):
        header = BytesIO()
        np.lib.format.write_array_header_1_0(header, {"descr": dtype, "fortran_order": False, "shape": shape})
        size = 8 * int(np.prod(shape))
        deflated, crc = _deflated_zeros(header.getvalue(), size)
        entries[f"{name}.npy"] = (deflated, crc, len(header.getvalue()) + size)
    path = folder / "bomb.npz"
    with open(path, "wb") as file:
        central = b""
        for name, (data, crc, size) in entries.items():
            offset = file.tell()
            file.write(struct.pack("<4s5H3L2H", b"PK\x03\x04", 20, 0, 8, 0, 33, crc, len(data), size, len(name), 0))
            file.write(name.encode() + data)
            central += struct.pack("<4s6H3L5H2L", b"PK\x01\x02", 20, 20, 0, 8, 0, 33, crc, len(data), size, len(name),
                                   0, 0, 0, 0, 0, offset) + name.encode()
        start = file.tell()
        file.write(central)
        file.write(struct.pack("<4s4H2LH", b"PK\x05\x06", 0, 0, len(entries), len(entries), len(central), start, 0))
    assert path.stat().st_size < 3_000_000
    assert sum(info.file_size for info in zipfile.ZipFile(path).infolist()) > 2_000_000_000
    return path


def ply_count(folder: Path, square: nd.Packing) -> Path:
    path = folder / "count.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 100000000000\nproperty double x\nproperty double y\n"
                    "property double z\nproperty double radius\nend_header\n0.5 0.5 0.5 0.1\n")
    return path


def _json_packing(folder: Path, square: nd.Packing, name: str, **changes) -> Path:
    path = square.save(folder / name)
    document = json.loads(path.read_text())
    document.update(changes)
    path.write_text(json.dumps(document))
    return path


def json_deep(folder: Path, square: nd.Packing) -> Path:
    path = _json_packing(folder, square, "deep.json", params="PARAMS")
    path.write_text(path.read_text().replace('"PARAMS"', "[" * 200_000 + "]" * 200_000))
    return path


def json_params(folder: Path, square: nd.Packing) -> Path:
    return _json_packing(folder, square, "params.json", params="x")


def json_dim(folder: Path, square: nd.Packing) -> Path:
    return _json_packing(folder, square, "dim.json", dim=10**9, centers=[], radii=[], rounds=[],
                         stats={"time": [], "count": [], "fill": []}, medial_axis=[], medial_radii=[])


def _recording(folder: Path, square: nd.Packing, name: str, **params) -> Path:
    packing = nd.Packing(square.centers, square.radii, square.rounds, square.volume, params={**square.params, **params})
    return packing.save(folder / name)


def source_box(folder: Path, square: nd.Packing) -> Path:
    return _recording(folder, square, "box-source.npz", source="box:dim=1000000000")


def source_simplex(folder: Path, square: nd.Packing) -> Path:
    return _recording(folder, square, "simplex-source.npz", source="simplex:dim=30000")


def yaml_bomb(folder: Path, square: nd.Packing) -> Path:
    """Under 600 bytes of YAML merges (``<<:``) of aliases, each level nine copies of the one
    before: 9**9 entries once merged."""
    lines = ["a: &a {k0: 0, k1: 0, k2: 0, k3: 0, k4: 0, k5: 0, k6: 0, k7: 0, k8: 0}"]
    for before, name in zip("abcdefgh", "bcdefghi"):
        lines.append(f"{name}: &{name} {{<<: [{', '.join(['*' + before] * 9)}]}}")
    lines.append("collision_spheres: {body: [{center: [0, 0, 0], radius: 0.1}]}")
    path = folder / "bomb.yml"
    path.write_text("\n".join(lines) + "\n")
    assert path.stat().st_size < 600
    return path


def sph_levels(folder: Path, square: nd.Packing) -> Path:
    path = folder / "levels.sph"
    path.write_text("1000000000 1000000000\n0.5 0.5 0.5 0.1 1")
    return path


#: name -> (make the file, the shape verify is given, the words of the one-line error, commands).
CASES = {
    "npz header of (10**9, 2)": (npz_header, "box:dim=2", "its centers.npy declares 1000000000x2 float64", None),
    "zip bomb of 2 GB": (zip_bomb, "box:dim=2", "would unpack to 2,000,003,856 bytes", None),
    "PLY of 10**11 vertices": (ply_count, "box:dim=3", "declares 100,000,000,000 vertices", None),
    "JSON nested 200,000 deep": (json_deep, "box:dim=2", "nested too deep", None),
    "JSON params 'x'": (json_params, "box:dim=2", "its params 'x' is not a mapping", None),
    "JSON dim 10**9": (json_dim, "box:dim=2", "its dimension 1,000,000,000 is more than ndpack reads", None),
    "recorded box:dim=10**9": (source_box, None, "dim must be a positive integer of at most", ("verify", "render")),
    "recorded simplex:dim=30000": (source_simplex, None, "dim must be a positive integer of at most",
                                   ("verify", "render")),
    "YAML alias bomb": (yaml_bomb, "box:dim=3", "uses the YAML alias", None),
    "sph of 10**9 levels": (sph_levels, "box:dim=3", "1000000000-level tree of branching 1000000000", None),
}


def _commands(path: Path, folder: Path, shape: str | None, which) -> list[list[str]]:
    commands = {"info": ["info", str(path)],
                "verify": ["verify", str(path), *(["--shape", shape] if shape else [])],
                "render": ["render", str(path), "-o", str(folder / f"{path.stem}.png")]}
    return [commands[name] for name in which or ("info", "verify", "render")]


@pytest.mark.parametrize("case", list(CASES))
def test_a_hostile_file_is_refused_in_one_line_quickly_and_cheaply(case, folder, square, ceiling):
    make, shape, words, which = CASES[case]
    path = make(folder, square)
    commands = _commands(path, folder, shape, which)
    report = run_child(commands, ceiling)
    for argv, result in zip(commands, report["results"]):
        lines = result["stderr"].strip().splitlines()
        assert result["code"] == 2 and len(lines) == 1, (argv, result)
        assert lines[0].startswith("ndpack: error: ") and "Traceback" not in result["stderr"], (argv, result)
        assert words in lines[0], (argv, lines[0])
        assert result["seconds"] < SECONDS, (argv, result["seconds"])
    assert report["peak"] <= ceiling


def test_printed_metadata_has_its_control_characters_escaped(folder, square, ceiling):
    """A file's text reaches the terminal escaped (``\\x1b``), never as escapes it would obey."""
    evil = "\x1b]0;owned\x07\x1b[2J"
    repair = {"outside": 1, "overlapping_pairs": 0, "shrunk": 1, "dropped": 0, "worst_poke_out": 0.1,
              "worst_overlap": None, "cause": f"a cause {evil}"}
    packing = nd.Packing(square.centers, square.radii, square.rounds, square.volume, stop_reason=f"count{evil}",
                         repair=repair, params={"source": f"box:dim=2{evil}", "note": f"see {evil}",
                                                f"key{evil}": 1, "holes": f"cap{evil}"})
    path = packing.save(folder / "escapes.npz")
    commands = _commands(path, folder, None, None)
    info, verify, render = run_child(commands, ceiling)["results"]
    for result in (info, verify, render):
        assert "\x1b" not in result["stdout"] + result["stderr"] and "\x07" not in result["stdout"] + result["stderr"]
        assert "Traceback" not in result["stderr"]
    assert info["code"] == 0 and info["stdout"].count("\\x1b]0;owned\\x07\\x1b[2J") >= 5, info["stdout"]
    for result in (verify, render):
        assert result["code"] == 2 and len(result["stderr"].strip().splitlines()) == 1, result
        assert "\\x1b" in result["stderr"]


# ------------------------------------------------------------------------------ through the API
def test_the_api_refuses_them_as_the_command_line_does(folder, square):
    for make, _, words, _ in CASES.values():
        if make in (source_box, source_simplex):
            continue
        with pytest.raises(nd.NdpackError, match="is not a readable ndpack packing") as info:
            nd.Packing.load(make(folder, square))
        assert words in str(info.value)


@pytest.mark.parametrize("changes, words", [
    (dict(params=["x"]), "its params ['x'] is not a mapping"),
    (dict(repair="x"), "its repair 'x' is not a mapping"),
    (dict(repair={"shrunk": -1}), "its repair.shrunk -1 is not a count"),
    (dict(stop_reason=3), "its stop_reason 3 is not a word"),
    (dict(version="1"), "its format version '1' is not a whole number"),
    (dict(dim=2.5), "its dimension 2.5 is not a positive integer"),
    (dict(dim=limits.MAX_DIM + 1), f"its dimension {limits.MAX_DIM + 1} is more than ndpack reads"),
    (dict(params={"source": ["box"]}), "its params.source ['box'] is not text"),
    (dict(params={"period": [1.0]}), "its params.period [1.0] is not one period"),
    (dict(params={"period": [1.0, -1.0]}), "is not one period"),
    (dict(params={"bounds": [[0, 0]]}), "its params.bounds [[0, 0]] is not two corners of 2 numbers"),
    (dict(params={"deep": json.loads("[" * 70 + "]" * 70)}), "nested more than 64 levels deep"),
    (dict(stats="x"), "its stats 'x' is not a mapping"),
    (dict(stats={"time": [1.0], "count": [], "fill": []}), "its round statistics have 1 times, 0 counts"),
    (dict(volume=0), "its volume 0 is not a positive number"),
])
def test_metadata_of_the_wrong_types_is_refused(folder, square, changes, words):
    path = _json_packing(folder, square, "typed.json", **changes)
    with pytest.raises(nd.NdpackError, match="is not a readable ndpack packing") as info:
        nd.Packing.load(path)
    assert words in str(info.value)


def test_declared_counts_are_checked_against_the_file(folder, square):
    """PLY (binary, a negative count), VTP, CSV and sph declare sizes that the file cannot hold."""
    ply = square.save(folder / "count.ply")
    raw = ply.read_bytes()
    (folder / "negative.ply").write_bytes(raw.replace(b"element vertex 10", b"element vertex -1"))
    vtp = square.save(folder / "count.vtp")
    text = vtp.read_text()
    (folder / "count-big.vtp").write_text(text.replace('NumberOfPoints="10"', 'NumberOfPoints="10000000000000"'))
    (folder / "count-small.vtp").write_text(text.replace('NumberOfPoints="10"', 'NumberOfPoints="9"'))
    csv = square.save(folder / "dim.csv")
    (folder / "dim-big.csv").write_text(csv.read_text().replace('"dim": 2', '"dim": 1000000000', 1))
    (folder / "one.sph").write_text("1 1\n0 0 0 1 1\n")
    (folder / "chain.sph").write_text("1000000000 1\n" + "0 0 0 1 1\n" * 1000)
    expected = {
        "negative.ply": "it declares -1 vertices",
        "count-big.vtp": "it declares 10,000,000,000,000 points",
        "count-small.vtp": "it declares 9 points, but its Points array holds 30 numbers",
        "dim-big.csv": "its dimension 1,000,000,000 is more than ndpack reads",
        "chain.sph": "a 1000000000-level tree of branching 1 has at least 1,001 nodes; found 1,000",
    }
    for name, words in expected.items():
        with pytest.raises(nd.NdpackError) as info:
            nd.Packing.load(folder / name)
        assert words in str(info.value), name
    assert len(nd.Packing.load(folder / "one.sph")) == 1


def test_an_xml_entity_bomb_is_refused(folder):
    """VTP files are read by expat, whose limit on entity expansion (2.4 and later) stops a billion laughs."""
    entities = ['<!ENTITY l0 "lollollollollollollollollollol">']
    entities += [f'<!ENTITY l{i} "{("&l" + str(i - 1) + ";") * 10}">' for i in range(1, 10)]
    path = folder / "laughs.vtp"
    path.write_text('<?xml version="1.0"?>\n<!DOCTYPE lolz [\n' + "\n".join(entities) + "\n]>\n"
                    '<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="1"><Points>'
                    '<DataArray type="Float64" format="ascii">&l9;</DataArray></Points></Piece></PolyData></VTKFile>\n')
    with pytest.raises(nd.NdpackError, match="is not a readable ndpack packing"):
        nd.Packing.load(path)


def test_yaml_nested_past_the_stack_is_refused(folder):
    path = folder / "deep.yml"
    path.write_text("collision_spheres: " + "[" * 100_000 + "]" * 100_000 + "\n")
    with pytest.raises(nd.NdpackError, match="nested"):
        nd.Packing.load(path)


def test_an_npz_member_must_hold_what_its_header_declares(folder, square):
    """Short of its header (a lying header), of a type that is not numbers, or sized against the
    other arrays: each refused from the headers, before any array is read."""
    members = _members(square)
    cases = {
        "short": ({"radii.npy": members["radii.npy"][:-8]},
                  "its radii.npy declares 10 float64 (80 bytes), but holds 72"),
        "void": ({"radii.npy": _npy(np.zeros(10, dtype="V8"))}, "its radii.npy holds |V8, not numbers"),
        "rows": ({"centers.npy": _npy(np.zeros((7, 2)))}, "it has 7 centres, 10 radii and 10 rounds"),
        "medial": ({"medial_axis.npy": _npy(np.zeros((3, 2)))}, "it has 3 medial-axis points and 0 medial radii"),
        "npy": (None, "it is a single NumPy array (.npy)"),
    }
    for name, (changes, words) in cases.items():
        path = folder / f"{name}.npz"
        if changes is None:
            path.write_bytes(_npy(np.zeros((10**9, 2), dtype=np.uint8)[:0]).replace(b"(0, 2)", b"(1000000000, 2)"))
        else:
            _zip(path, {**members, **changes})
        with pytest.raises(nd.NdpackError) as info:
            nd.Packing.load(path)
        assert words in str(info.value), name


def test_a_recorded_shape_is_compared_by_dimension_before_it_is_built(folder, square, capsys):
    """A 2-D packing recording a 250-D simplex (within MAX_DIM): refused from the spec, unbuilt."""
    from ndpack.cli import main
    from ndpack.io.shape_sources import load_shape, source_dim

    assert source_dim("simplex:dim=250") == 250 and source_dim("box") == 3 and source_dim("square") == 2
    assert source_dim("part.stl") == 3
    path = _recording(folder, square, "simplex250.npz", source="simplex:dim=250")
    assert main(["verify", str(path)]) == 2
    assert "the shape simplex:dim=250 is 250-D, but the packing is 2-D" in capsys.readouterr().err
    assert main(["verify", str(square.save(folder / "plain.npz")), "--shape", "torus"]) == 2
    assert "the shape torus is 3-D, but the packing is 2-D" in capsys.readouterr().err
    with pytest.raises(nd.DimensionError, match="is 3-D, but the packing is 2-D"):
        load_shape("torus:dim=2", dim=2)  # the spec says 2; the torus built is 3-D
