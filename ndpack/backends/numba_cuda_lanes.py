"""Cooperative moves on numba-cuda: the 32 threads of a block walk one prototype's mesh tree together.

The design is Warp's (:mod:`ndpack.backends.warp_lanes`, whose docstring says why: a move launch of
few prototypes lasts as long as its slowest prototype's chain of dependent tree-node visits). Every
lane of a block of :data:`LANES` threads runs the prototype's whole move, the same numbers and so
the same branches; only the walk is shared (``nearest_element_lanes``): each round the lanes pop up
to one node each from a stack in the block's shared memory, test it, push the children that may
hold something nearer (each lane's two in lane order: a ballot counts the pushes of the lanes
below), and agree on the best distance so far (a butterfly of shuffles). Lane 0 writes.

One kernel serves both launches, so that numba-cuda compiles the move (the longest of its
compiles) once: ``move_ids`` (which also runs the backend's converge) runs the ``_lanes`` copies of
the chain from the move to the walk (:func:`ndpack.backends.warp_lanes.chain_copies`), and the walk
is cooperative only in a block of exactly :data:`LANES` threads (the backend's cooperative launch:
a block per prototype); in any other launch each thread walks alone, as the serial kernel does.

The answer is the walk's: the nearest element closer than the limit, and of equal distances the
smallest id (the serial walk keeps the first it meets). A stack that would overflow makes every
lane walk alone. Numba's CUDA simulator has no warp intrinsics: there the ballot and the shuffles
are replaced by the same sums and minima through shared memory (:func:`lanes_text`), so the
tests run the walk's logic, and ``bench/cuda_compile.py`` compiles the GPU's text without a GPU.
"""

from __future__ import annotations

from .warp_lanes import COOPERATIVE_MOST, CONVERGE_MOST, STACK_CAPACITY, chain_copies, visit_node

__all__ = ["CHAIN", "CONVERGE_MOST", "COOPERATIVE_MOST", "LANES", "has_walk", "lanes_text", "shared_bytes"]

#: Threads of a cooperative block: one warp (the ballot's and the shuffles' mask is the whole warp).
LANES = 32
#: The numba functions on the way from the move to the tree walk, copied with the ``_lanes`` suffix
#: (the program's, then ``move_kernels``'s, as printed for Numba).
CHAIN = ("surface_feature", "sd_feature", "nearest_obstacle", "free_space", "converge_from", "move_one")

_WALK = '''
def nearest_element_lanes(q, prm, o, limit):
    """nearest_element, walked by the lanes of a block of LANES threads together (one prototype's;
    ndpack.backends.numba_cuda_lanes); in any other block each thread walks alone."""
    if cuda.blockDim.x != LANES:
        return nearest_element(q, prm, o, limit)
    nodes = int(prm[o + 7])
    elements = int(prm[o + 8])
    stride = int(prm[o + 10])
    size = 2 * D + 2
    lane = cuda.threadIdx.x
    # The launch's dynamic shared memory (SHARED_BYTES): the stack, then its height and whether a push
    # was lost. (A static array in a device function reached by two paths is defined twice at link.)
    pending = cuda.shared.array(0, int32)
    cuda.syncthreads()  # the last walk's reads of the state are over
    if lane == 0:
        pending[0] = 0
        pending[CAPACITY] = 1
        pending[CAPACITY + 1] = 0
    cuda.syncthreads()
    best = limit  # the block's best distance, known every round
    mine = limit  # this lane's
    found = -1
    while pending[CAPACITY] > 0 and pending[CAPACITY + 1] == 0:
        top = pending[CAPACITY]
        take = min(top, LANES)
        node = -1
        if lane < take:
            node = pending[top - 1 - lane]
        cuda.syncthreads()  # every lane has popped before any pushes
        far = -1
        near = -1
        if node >= 0:
VISIT_NODE
        # Each lane's far child, then its near one (popped first), after the lanes below.
        below, pushed = lanes_pushes(far >= 0, near >= 0, lane)
        slot = top - take + below
        if far >= 0:
            if slot < CAPACITY:
                pending[slot] = far
            slot += 1
        if near >= 0 and slot < CAPACITY:
            pending[slot] = near
        best = min(best, lanes_min(mine, lane))
        if lane == 0:
            height = top - take + pushed
            pending[CAPACITY] = min(height, CAPACITY)
            if height > CAPACITY:
                pending[CAPACITY + 1] = 1
        cuda.syncthreads()
    if pending[CAPACITY + 1] != 0:
        return nearest_element(q, prm, o, limit)
    # Of the lanes holding the best distance, the smallest element (-1 where none was nearer; ids are
    # exact in float64).
    key = 2147483647.0
    if mine == lanes_min(mine, lane):
        key = float(found)
    return int(lanes_min(key, lane))
'''

_WARP_INTRINSICS = '''
def lanes_pushes(far, near, lane):
    """Pushes of the lanes below this one, and of all: a ballot of each child."""
    far_lanes = cuda.ballot_sync(0xFFFFFFFF, far)
    near_lanes = cuda.ballot_sync(0xFFFFFFFF, near)
    below = (1 << lane) - 1
    return (cuda.popc(far_lanes & below) + cuda.popc(near_lanes & below),
            cuda.popc(far_lanes) + cuda.popc(near_lanes))


def lanes_min(value, lane):
    """The least ``value`` of the warp's lanes, in every lane."""
    shift = 16
    while shift > 0:
        value = min(value, cuda.shfl_xor_sync(0xFFFFFFFF, value, shift))
        shift //= 2
    return value

'''

# The simulator's: one shared array a line (it tells allocations apart by their line).
_SHARED_MEMORY = '''
def lanes_pushes(far, near, lane):
    """Pushes of the lanes below this one, and of all, through shared memory."""
    counts = cuda.shared.array(LANES, int32)
    cuda.syncthreads()
    counts[lane] = (1 if far else 0) + (1 if near else 0)
    cuda.syncthreads()
    below = 0
    pushed = 0
    for k in range(LANES):
        if k < lane:
            below += counts[k]
        pushed += counts[k]
    return below, pushed


def lanes_min(value, lane):
    """The least ``value`` of the block's lanes, in every lane, through shared memory."""
    values = cuda.shared.array(LANES, float64)
    cuda.syncthreads()
    values[lane] = value
    cuda.syncthreads()
    least = values[0]
    for k in range(1, LANES):
        least = min(least, values[k])
    return least

'''


def shared_bytes(capacity: int = STACK_CAPACITY) -> int:
    """Dynamic shared memory a cooperative launch gives each block: the walk's stack and state (int32)."""
    return 4 * (int(capacity) + 2)


def has_walk(text: str) -> bool:
    """Whether a numba module's text walks a mesh's (or outline's) tree."""
    return "def nearest_element(" in text


def lanes_text(text: str, simulator: bool = False, capacity: int = STACK_CAPACITY) -> str:
    """The cooperative chain of a numba-cuda module whose ``text`` holds the program and the
    kernels (``numba_common.KERNELS``): the :data:`CHAIN` functions present copied with the suffix,
    and where the program walks a tree, the walk (its stack holding ``capacity`` nodes) and its lane primitives,
    through shared memory for the ``simulator``."""
    present = [name for name in CHAIN if f"\ndef {name}(" in "\n" + text]
    parts = ["# Cooperative moves: see ndpack.backends.numba_cuda_lanes.",
             f"LANES = {LANES}", f"CAPACITY = {int(capacity)}", *chain_copies(text, present, decorator="")]
    if has_walk(text):
        parts += [_WALK.replace("VISIT_NODE", visit_node(12)), _SHARED_MEMORY if simulator else _WARP_INTRINSICS]
    return "\n\n".join(parts) + "\n"
