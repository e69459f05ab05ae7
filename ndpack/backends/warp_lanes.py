"""Cooperative moves on a GPU: the threads of a block walk one prototype's mesh tree together.

A move launch of few prototypes lasts as long as its slowest prototype's chain of dependent
tree-node visits: a point near the medial axis of a limb sees a ring of surface at almost its own
distance, and one nearest-element query visits a thousand nodes of the armadillo's tree (against
a mean of 50). Such a launch gives each prototype several threads
(:func:`ndpack.backends.prototypes.lane_spread`); when it moves at most :data:`COOPERATIVE_MOST`
prototypes, the backend launches :data:`MOVE_KERNEL` instead: a block of :data:`LANES` threads per
prototype, from a module of its own (:func:`functions_only`). Every lane of the block runs the
prototype's whole move (the same numbers, so the same branches), and only the walk is shared
(:func:`nearest_lanes`): each round the lanes pop up to one node each from a stack in the block's
shared memory, test it, push the children that may hold something nearer, and agree on the best
distance so far (every :data:`SHARE_EVERY` rounds). A query's chain shrinks from the nodes it
visits to about their number over the lanes plus the tree's depth: ``bench/cooperative_walk.py``
counts 1,273 nodes against 47 rounds at the armadillo's worst point, 47 against 16 on the mean.

The answer is the walk's: the nearest element closer than the limit (of equal distances, the
smallest id; the serial walk keeps the first it meets). A stack that would overflow makes every
lane walk alone, as the serial kernel does.

The functions between the move kernel and the walk are the serial ones, copied with a ``_lanes``
suffix by :func:`lanes_text` (the only change: they call the ``_lanes`` versions), so there is
one description of a move. numba-cuda has its own walk, of the same design
(:mod:`ndpack.backends.numba_cuda_lanes`). A program without a tree walk (no mesh or outline, or
float32, where Warp's own ``wp.Mesh`` answers) gets no cooperative kernel.
"""

from __future__ import annotations

import re

#: The serial functions on the way from the move kernel to the tree walk, in the order they are
#: copied (callers after callees is not needed: Warp resolves names at the module's end).
CHAIN = ("surface_feature", "sd_feature", "nearest_obstacle", "free_space", "converge_from", "move_one")
#: Nodes the block's shared stack holds (int32: 4 KB a block); more make the lanes walk alone.
#: The armadillo's deepest stack at 32 lanes was 310 (no limit) and 121 (the last step's element).
STACK_CAPACITY = 1024
#: The lanes agree on the best distance every this many rounds; in between each prunes by its own
#: (and the limit). Agreeing is not what a round costs: the move launches took 0.524, 0.522 and
#: 0.516 s sharing every 1, 4 and 16 rounds (H200, armadillo at 100,000; bench/gpu_issue48_step4.sh
#: share), so the lanes agree every round, which prunes most.
SHARE_EVERY = 1
#: Suffix of the copies.
SUFFIX = "_lanes"
#: Threads of a cooperative block: one warp. Its module is compiled for this block size alone
#: (Warp compiles a module once per block size it is launched with).
LANES = 32
#: On a GPU, a move launch of at most this many prototypes is cooperative: 4,096 blocks of 32
#: stay resident together on an H100 (its limits: 32 blocks on each of 132 SMs). The device's time at 100,000
#: spheres of the armadillo on an H200 (bench/gpu_issue48_step3.sh lanes), with moves of at most
#: 1,024, 4,096, 8,192 and 16,384 prototypes cooperative: 0.93, 0.80, 0.88 and 0.88 s; never 1.28 s.
COOPERATIVE_MOST = 4096
#: The same for the converge of a packing's set-up (a :data:`MOVE_KERNEL` launch), one launch over every
#: cell: at 100,000 spheres of the armadillo 5,018 cells, whose slowest walked 10x the mean's nodes
#: (bench/work_model.py), so the longest chain outweighs a second wave of blocks: the set-up took
#: 0.06 s against 0.24 s (H200, bench/gpu_issue48_step4.sh lanes).
CONVERGE_MOST = 8192

#: One lane's visit of ``node`` in a cooperative walk, the same in Warp's and numba-cuda's walks (both
#: dialects read it alike): a leaf's elements nearer than this lane's best (``mine``; of equal distances
#: the smaller id) update ``mine`` and ``found``; an inner node's children that may hold something nearer
#: than the block's ``best`` become ``far`` and ``near`` (-1: none), the nearer to be popped first.
_VISIT_NODE = '''
b = nodes + size * node
if box_squared_distance(q, prm, b) < best:
    count = int(prm[b + 2 * D + 1])
    if count > 0:
        start = int(prm[b + 2 * D])
        for k in range(start, start + count):
            d = element_query(q, prm, elements + stride * k, 0)
            if d < mine or (d == mine and k < found):
                mine = d
                found = k
    else:
        left = node + 1
        right = int(prm[b + 2 * D])
        near_left = box_squared_distance(q, prm, nodes + size * left)
        near_right = box_squared_distance(q, prm, nodes + size * right)
        if near_left <= near_right:
            if near_right < best:
                far = right
            if near_left < best:
                near = left
        else:
            if near_left < best:
                far = left
            if near_right < best:
                near = right
'''


def visit_node(indent: int) -> str:
    """:data:`_VISIT_NODE`'s text, each line indented by ``indent`` spaces."""
    return "\n".join(" " * indent + line if line else line for line in _VISIT_NODE.strip("\n").split("\n"))


_NEAREST_LANES = '''
@wp.func
def nearest_element_lanes(q: Any, prm: wp.array(dtype=F), o: int, limit: F):
    """nearest_element, walked by the lanes of the block together (ndpack.backends.warp_lanes)."""
    nodes = int(prm[o + 7])
    elements = int(prm[o + 8])
    stride = int(prm[o + 10])
    size = 2 * D + 2
    lane = wp.untile(wp.tile_scan_exclusive(wp.tile(int(1))))
    pending = wp.tile_stack(capacity=CAPACITY, dtype=int)
    wp.tile_stack_push(pending, 0, lane == 0)
    best = limit  # the best this lane knows of: its own, and the block's every SHARE rounds
    mine = limit  # this lane's
    found = int(-1)
    lost = int(0)
    rounds = int(0)
    while wp.tile_stack_count(pending) > 0:
        rounds += 1
        node, slot = wp.tile_stack_pop(pending)
        far = int(-1)
        near = int(-1)
        if slot >= 0:
VISIT_NODE
        # The nearer child last, so that it is popped first (a later push pops first).
        kept_far = wp.tile_stack_push(pending, far, far >= 0)
        kept_near = wp.tile_stack_push(pending, near, near >= 0)
        if (far >= 0 and kept_far < 0) or (near >= 0 and kept_near < 0):
            lost = 1
        if rounds % SHARE == 0:  # the same in every lane: the block agrees
            best = wp.min(best, wp.tile_min(wp.tile(mine))[0])
        else:
            best = wp.min(best, mine)
    if wp.tile_max(wp.tile(lost))[0] > 0:
        return nearest_element(q, prm, o, limit)
    # Of the lanes holding the best distance, the smallest element (-1 where none was nearer).
    best = wp.tile_min(wp.tile(mine))[0]
    key = int(2147483647)
    if mine == best:
        key = found
    return F(wp.tile_min(wp.tile(key))[0])
'''



def nearest_lanes(capacity: int = STACK_CAPACITY, share: int = SHARE_EVERY) -> str:
    """Warp text of ``nearest_element_lanes``, its stack holding ``capacity`` nodes, the lanes
    agreeing on the best distance every ``share`` rounds."""
    return (_NEAREST_LANES.replace("VISIT_NODE", visit_node(12)).replace("CAPACITY", str(int(capacity)))
            .replace("SHARE", str(int(share))))


MOVE_KERNEL = '''
@wp.kernel
def move_ids_lanes(ids: wp.array(dtype=wp.int32), first: wp.array(dtype=VecD), first_rows: int, tries: int,
                   stream: wp.uint64, points: wp.array(dtype=VecD), clearance: wp.array(dtype=F),
                   polished: wp.array(dtype=wp.int32), lower: wp.array(dtype=VecD), upper: wp.array(dtype=VecD),
                   wall: wp.array(dtype=F), prm: wp.array(dtype=F), centers: wp.array(dtype=VecD),
                   radii: wp.array(dtype=F), nbr: wp.array2d(dtype=wp.int32), steps: wp.array(dtype=F), h: F,
                   polish: int, spread: int, polish_steps: wp.array(dtype=F), polish_low: F, polish_from: int):
    """move_ids with a block of ``spread`` lanes per prototype (a tiled launch), walking together."""
    b, lane = wp.tid()
    move_one_lanes(b, lane, ids, first, first_rows, tries, stream, points, clearance, polished, lower, upper, wall,
                   prm, centers, radii, nbr, steps, h, polish, polish_steps, polish_low, polish_from)
'''


def functions_only(kernels: str) -> str:
    """Warp ``kernels``' text without its kernels: the functions a copy may call (Warp compiles a
    function only where a kernel calls it)."""
    return re.sub(r"^@wp\.kernel\n.*?(?=^\S)", "", kernels + "\n#", flags=re.M | re.S)

def has_walk(text: str) -> bool:
    """Whether a module's text walks a mesh's (or outline's) tree in the kernel language."""
    return "def nearest_element(" in text and "wp.mesh_query_point" not in text


def definition(text: str, name: str, decorator: str = "@wp.func\n") -> str:
    """The text of the top-level function ``name`` in ``text``, with its ``decorator`` line."""
    found = re.search(rf"^{re.escape(decorator)}def {name}\(.*?(?=^\S)", text + "\n#", flags=re.M | re.S)
    if found is None:
        raise ValueError(f"no function {name} in the module's text: the cooperative chain is out of date")
    return found.group(0)


def chain_copies(text: str, chain, decorator: str = "@wp.func\n") -> list[str]:
    """The functions ``chain`` of ``text`` copied with :data:`SUFFIX`, each calling the copies (and
    ``nearest_element_lanes``) in place of the originals: the way from a move to the tree walk."""
    calls = re.compile(r"\b(" + "|".join((*chain, "nearest_element")) + r")\(")
    return [calls.sub(lambda m: m.group(1) + SUFFIX + "(", definition(text, name, decorator)) for name in chain]


def lanes_text(text: str, capacity: int = STACK_CAPACITY, share: int = SHARE_EVERY) -> str:
    """The cooperative move of a module whose ``text`` (program and kernels) walks a tree
    (:func:`has_walk`): the :data:`CHAIN` copied with the suffix, the walk (:func:`nearest_lanes`),
    and :data:`MOVE_KERNEL`."""
    return "\n\n".join(["# Cooperative moves: see ndpack.backends.warp_lanes.", nearest_lanes(capacity, share),
                        *chain_copies(text, CHAIN), MOVE_KERNEL])
