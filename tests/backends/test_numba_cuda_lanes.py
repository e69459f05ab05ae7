"""Cooperative moves on numba-cuda (ndpack.backends.numba_cuda_lanes): the block's walk finds what
the serial walk finds, and a packing with cooperative moves agrees with the CPU's packing. Without a
GPU the ``small`` tests run in a fresh process under Numba's CUDA simulator (slowly: each lane is a
Python thread), whose lane primitives go through shared memory."""

import os
import subprocess
import sys

import numpy as np
import pytest
import trimesh

import ndpack as nd
from ndpack.backends import get_backend
from ndpack.backends.numba_common import KERNELS
from ndpack.backends.numba_cuda_lanes import CHAIN, LANES, has_walk, lanes_text, shared_bytes
from ndpack.errors import BackendError
from ndpack.kernels.compile import numba_namespace
from ndpack.kernels.compiled import compiled_program
from walk_checks import check_against_serial

SIMULATED = os.environ.get("NUMBA_ENABLE_CUDASIM") == "1"


def _cuda_works() -> bool:
    try:
        get_backend("numba-cuda")
        return True
    except BackendError:
        return False


CUDA = _cuda_works()
needs_cuda = pytest.mark.skipif(not CUDA, reason="numba-cuda has no GPU here (the simulator runs these in a child)")

TEST_KERNEL = '''
def nearest_both(points, prm, o, limits, out):
    i = cuda.blockIdx.x
    q = point()
    for k in range(D):
        q[k] = points[i, k]
    shared = nearest_element_lanes(q, prm, o, limits[i])
    alone = nearest_element(q, prm, o, limits[i])
    if cuda.threadIdx.x == 0:
        out[i, 0] = shared
        out[i, 1] = alone
        elements = int(prm[o + 8])
        stride = int(prm[o + 10])
        out[i, 2] = -1.0
        out[i, 3] = -1.0
        if shared >= 0:
            out[i, 2] = element_query(q, prm, elements + stride * shared, 0)
        if alone >= 0:
            out[i, 3] = element_query(q, prm, elements + stride * alone, 0)
'''


def lumpy_sphere(subdivisions=1):
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    lumps = 1.0 + 0.3 * np.sin(3 * sphere.vertices[:, 0]) * np.cos(2 * sphere.vertices[:, 1])
    return nd.TriangleMesh(sphere.vertices * lumps[:, None] + [0.2, -0.1, 0.3], sphere.faces)


def test_a_plain_launch_is_never_taken_for_a_cooperative_one():
    """The kernels tell a cooperative launch by its block of LANES threads."""
    from ndpack.backends.numba_cuda_backend import THREADS_PER_BLOCK

    assert THREADS_PER_BLOCK != LANES


def test_copies_call_the_cooperative_chain():
    shape = lumpy_sphere()
    source = compiled_program(shape).program.source("cuda")
    assert has_walk(source)
    for simulator in (False, True):
        text = lanes_text(source + "\n\n" + KERNELS, simulator=simulator)
        copies = text.split("# Cooperative moves")[1]
        for name in CHAIN:
            assert f"def {name}_lanes(" in copies
            assert f" {name}(" not in copies.replace(f"def {name}_lanes(", "")
        assert ("cuda.ballot_sync" in text) is not simulator  # the simulator has no warp intrinsics
    # A shape without a tree walk gets the copies and no walk.
    box = compiled_program(nd.Box([0.0, 0.0], [1.0, 1.0])).program.source("cuda")
    if not has_walk(box):
        assert "def nearest_element_lanes(" not in lanes_text(box + "\n\n" + KERNELS)


@needs_cuda
@pytest.mark.parametrize(("capacity", "lanes"), [(1024, LANES), (2, LANES), (1024, 8)],
                         ids=["cooperative", "overflowing stack", "a block of another size walks alone"])
def test_small_cooperative_walk_finds_the_serial_nearest(capacity, lanes):
    from numba import cuda

    shape = lumpy_sphere()
    flat = compiled_program(shape)
    program = flat.program
    source = program.source("cuda")
    text = KERNELS + lanes_text(source + "\n\n" + KERNELS, simulator=SIMULATED, capacity=capacity) + TEST_KERNEL

    def jit(namespace, names):
        for name in names:
            namespace[name] = cuda.jit(namespace[name]) if name == "nearest_both" else cuda.jit(device=True)(
                namespace[name])

    kernel = numba_namespace(program, "cuda", text, jit)["nearest_both"]
    o = int(flat.params[1])
    rng = np.random.default_rng(7)
    points = rng.uniform(-0.8, 0.8, (8 if SIMULATED else 200, 3))  # the surface's normalised coordinates
    prm = cuda.to_device(flat.params)

    def launch(limits):
        out = cuda.device_array((len(points), 4))
        kernel[len(points), lanes, 0, shared_bytes(capacity)](cuda.to_device(points), prm, o, cuda.to_device(limits),
                                                              out)
        return out.copy_to_host()

    check_against_serial(launch, len(points), serial=capacity == 2 or lanes != LANES)


@needs_cuda
def test_small_cooperative_converge_matches_the_cpu(monkeypatch):
    """A converge with a block of lanes per point (the chain's copies: restarts, steps, the walks,
    lane 0's writes) ends where numba's on the CPU ends."""
    from ndpack.drivers.greedy.protosphere import cooling_schedule

    shape = lumpy_sphere()
    rng = np.random.default_rng(3)
    count = 3 if SIMULATED else 300
    lower = rng.uniform(-0.4, 0.2, (count, 3))
    upper = lower + 0.25
    points = rng.uniform(lower, upper)
    starts = rng.uniform(lower, upper, (2, count, 3))
    centers, radii = np.array([[0.2, -0.1, 0.3]]), np.array([0.3])
    neighbours = np.zeros((count, 1), dtype=np.int64)
    steps = cooling_schedule(8 if SIMULATED else 30)
    cuda_backend = get_backend("numba-cuda")  # the process's own: changed for this test only
    monkeypatch.setattr(cuda_backend, "cooperative_converge_most", 4096)
    got = cuda_backend.converge(shape, points, lower, upper, centers, radii, neighbours, steps, starts=starts)
    expected = get_backend("numba").converge(shape, points, lower, upper, centers, radii, neighbours, steps,
                                             starts=starts)
    # Equal distances may pick another element, and a GPU fuses multiply-adds: the same node.
    np.testing.assert_allclose(got[1], expected[1], rtol=0, atol=1e-7)
    np.testing.assert_allclose(got[0], expected[0], rtol=0, atol=1e-4)


@pytest.mark.skipif(not CUDA or SIMULATED, reason="a GPU's test (too slow for the simulator)")
def test_cooperative_moves_pack_as_the_cpu(monkeypatch):
    """A packing whose moves and converges are all cooperative agrees with numba's on the CPU under
    a GPU's policies (equal distances may pick another element, so as packings, not bit for bit).
    GPU only: the simulator runs a block's 32 lanes as Python threads, too slowly for a packing."""
    shape = lumpy_sphere()
    count = 40
    packings = []
    for name in ("numba", "numba-cuda"):
        backend = get_backend(name)  # the process's own: changed for this test only
        monkeypatch.setattr(backend, "launch_bound", True)
        monkeypatch.setattr(backend, "move_spread", LANES, raising=False)
        monkeypatch.setattr(backend, "cooperative_most", 4096, raising=False)
        monkeypatch.setattr(backend, "cooperative_converge_most", 4096, raising=False)
        packings.append(nd.pack(shape, count, grid=4, mode="fast", backend=backend, seed=3, progress=False))
    cpu, cooperative = packings
    assert len(cpu) == len(cooperative) == count
    # A GPU fuses multiply-adds, which the zig-zag to a Voronoi node amplifies: 1.8e-6 of a radius
    # apart at the third sphere on an H100.
    np.testing.assert_allclose(np.sort(cooperative.radii)[-3:], np.sort(cpu.radii)[-3:], rtol=1e-4)
    assert cooperative.fill == pytest.approx(cpu.fill, rel=1e-2)
    assert cooperative.verify().ok


@pytest.mark.skipif(SIMULATED or CUDA, reason="runs only where there is no GPU")
def test_cooperative_walk_under_simulator():
    """The tests above, run by Numba's CUDA simulator in a fresh process (the switch must be set
    before numba.cuda is imported)."""
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1")
    result = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", __file__, "-k",
                             "small"], env=env, capture_output=True, text=True, timeout=1200)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
