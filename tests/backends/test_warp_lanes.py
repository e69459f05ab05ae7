"""Cooperative moves (ndpack.backends.warp_lanes): the block's walk finds what the serial walk
finds, and a packing with cooperative moves agrees with the packing without (equal distances may
pick another element). Warp's CPU device runs blocks of several lanes as fibers (``enable_cpu_blocks``), slowly:
small meshes only."""

import numpy as np
import pytest
import trimesh

import ndpack as nd
from ndpack.backends import get_backend
from ndpack.backends.warp_backend import KERNELS
from ndpack.backends.warp_lanes import functions_only, has_walk, lanes_text, nearest_lanes
from ndpack.kernels.compile import warp_module
from ndpack.kernels.compiled import compiled_program
from walk_checks import check_against_serial

wp = pytest.importorskip("warp")
wp.init()
# The walks run on Warp's CPU device (blocks as fibers); a GPU machine's Warp may have no CPU compiler.
needs_cpu = pytest.mark.skipif(not wp.is_cpu_available(), reason="Warp's CPU compiler is not available here")

TEST_KERNEL = '''
@wp.kernel
def nearest_both(points: wp.array(dtype=VecD), prm: wp.array(dtype=F), o: int, limits: wp.array(dtype=F),
                 out: wp.array2d(dtype=F)):
    i, lane = wp.tid()
    shared = nearest_element_lanes(points[i], prm, o, limits[i])
    alone = nearest_element(points[i], prm, o, limits[i])
    if lane == 0:
        out[i, 0] = shared
        out[i, 1] = alone
        elements = int(prm[o + 8])
        stride = int(prm[o + 10])
        out[i, 2] = F(-1.0)
        out[i, 3] = F(-1.0)
        if shared >= F(0.0):
            out[i, 2] = element_query(points[i], prm, elements + stride * int(shared), 0)
        if alone >= F(0.0):
            out[i, 3] = element_query(points[i], prm, elements + stride * int(alone), 0)
'''


@pytest.fixture
def cpu_blocks():
    saved = wp.config.enable_cpu_blocks
    wp.config.enable_cpu_blocks = True
    yield
    wp.config.enable_cpu_blocks = saved


def lumpy_sphere(subdivisions=2):
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    lumps = 1.0 + 0.3 * np.sin(3 * sphere.vertices[:, 0]) * np.cos(2 * sphere.vertices[:, 1])
    return nd.TriangleMesh(sphere.vertices * lumps[:, None] + [0.2, -0.1, 0.3], sphere.faces)


@needs_cpu
@pytest.mark.parametrize(("capacity", "share"), [(1024, 1), (1024, 3), (2, 1)],
                         ids=["stack", "sharing every 3 rounds", "overflowing stack"])
@pytest.mark.parametrize("lanes", [8, 32])
def test_cooperative_walk_finds_the_serial_nearest(cpu_blocks, capacity, share, lanes):
    shape = lumpy_sphere()
    flat = compiled_program(shape)
    program = flat.program
    assert has_walk(program.source("warp", "float64"))
    module = warp_module(program, "float64", nearest_lanes(capacity, share) + TEST_KERNEL, "cpu", block_dim=lanes,
                         what=" (a test of cooperative walks)")
    prm = wp.array(flat.params, dtype=wp.float64, device="cpu")
    o = int(flat.params[1])
    rng = np.random.default_rng(7)
    points = rng.uniform(-0.8, 0.8, (60, 3))  # the surface's own normalised coordinates

    def launch(limits):
        out = wp.zeros((len(points), 4), dtype=wp.float64, device="cpu")
        wp.launch_tiled(module.nearest_both, dim=[len(points)], inputs=[
            wp.array(points, dtype=module.VecD, device="cpu"), prm, o,
            wp.array(limits, dtype=wp.float64, device="cpu"), out], block_dim=lanes, device="cpu")
        return out.numpy()

    check_against_serial(launch, len(points), serial=capacity == 2)  # an overflow's fallback is the serial walk


def test_copies_call_the_cooperative_chain():
    shape = lumpy_sphere(1)
    source = compiled_program(shape).program.source("warp", "float64")
    text = lanes_text(source + "\n\n" + KERNELS)
    for name in ("surface_feature", "sd_feature", "nearest_obstacle", "free_space", "converge_from", "move_one"):
        assert f"def {name}_lanes(" in text
        assert f" {name}(" not in text.split("# Cooperative moves")[1].replace(f"def {name}_lanes(", "")
    assert "@wp.kernel" not in functions_only(KERNELS)
    assert "def converge_from(" in functions_only(KERNELS)
    assert "def move_ids_lanes(" in text and "converge_all" not in text  # the converge is a move launch
    assert not has_walk(compiled_program(shape).program.source("warp", "float32"))  # wp.Mesh answers there


@needs_cpu
def test_cooperative_moves_pack_as_the_plain_ones(cpu_blocks):
    shape = lumpy_sphere(1)
    packings = []
    for cooperative in (0, 4096):
        backend = get_backend("warp", device="cpu")
        backend.launch_bound, backend.move_spread = True, 32
        backend.cooperative_most = backend.cooperative_converge_most = cooperative
        packings.append(nd.pack(shape, 25, mode="fast", backend=backend, seed=3, progress=False))
    plain, shared = packings
    assert len(plain) == len(shared) == 25
    # Equal distances to elements sharing a vertex or an edge may pick another element, whose
    # closest point differs in the last bits; the greedy packing then drifts (2.8e-5 of a radius
    # at the 8th sphere here), so the two agree as packings, not bit for bit.
    np.testing.assert_allclose(np.sort(shared.radii)[-5:], np.sort(plain.radii)[-5:], rtol=1e-9)
    np.testing.assert_allclose(np.sort(shared.radii), np.sort(plain.radii), rtol=1e-3)
    assert shared.fill == pytest.approx(plain.fill, rel=1e-3)
    for packing in packings:
        assert packing.verify().ok
