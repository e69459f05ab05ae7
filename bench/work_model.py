"""The work a fast-mode packing gives a GPU, counted on the CPU: what predicts the GPU's time.

    python bench/work_model.py --mesh ../shared/data/meshes/armadillo.obj --count 100000 \\
        --against bench/results/profile_kernels_h100_armadillo_issue48.json \\
        --out bench/results/work_model_2core_armadillo_100k.json [--parts launches walks]
        [--constants EARLIER.json] [--split-ratio R]

Two runs of the same packing (fast mode, seed 0), each counting what its backend cannot show:

- ``launches``: the device store (``DevicePrototypes``) on Warp's CPU device with a GPU's
  policies (``launch_bound``: polishes ahead in the move launch; a move spread over ``SPREAD_MAX``
  threads), so that its host logic is the GPU's: per round and in all, the launches of each kernel
  (``move_ids`` split into moves, moves with a polish ahead, and polishes, as
  ``bench/profile_kernels.py`` splits them), their threads, and the host-device synchronisations
  (each ``fetch`` and ``synchronize``: a round trip that stalls the GPU's queue); and the host's
  own time in the rounds (their wall time less the launches', which the CPU device runs to the
  end before returning: the Python and NumPy work a GPU run does between launches) and the final
  check's time (its centre distances, which a GPU run computes in the rounds while its moves run,
  counted apart: ``check_in_rounds_s``).
- ``walks``: numba on one thread, with the converge kernel's text instrumented here (not in the
  package): per converge launch and per prototype, the mesh-tree nodes visited (every walk of the
  tree, ``nearest_element``'s above all) and the distance evaluations (``sd_feature`` calls). A
  launch on a GPU lasts about as long as its slowest thread, so a launch's critical path is its
  largest prototype's node count (numba makes a move with a polish ahead two launches, the GPU
  one: their paths are summed, an upper bound); the table gives their sum over the run against
  the mean's, and the threads a launch has (a GPU keeps about 270,000 resident on an H100).
  Beside each query, the rounds of the cooperative walk a GPU makes instead in a launch of few
  prototypes (:mod:`ndpack.backends.warp_lanes`): such a launch's critical path is its largest
  prototype's rounds.

``--against`` sets the counts beside a GPU run of the same packing (``bench/profile_kernels.py``,
every launch timed on the device): whether the launches match, kernel by kernel, and the constants
the GPU's times imply: seconds per critical-path node of a move launch, per other launch, and,
from a run with ``--stages``, the GPU host's time in the rounds (the rounds' stage less the
device's time) and its final check over this machine's, and the set-up's seconds. (The first
model's host term, seconds per synchronisation, did not carry from one mesh to another: 47% off.)
``--constants`` predicts the GPU's time from the counts with an earlier run's constants (its
``against``), and with ``--against`` too sets it beside what the GPU took: the model's test.
``--split-ratio`` counts a variant: the GPU's split ratio (``rounds.SPLIT_RATIO_AHEAD``).

Counting changes nothing in the packing: the instrumented kernels write their counts into a
tail appended to the shape's numbers, which no shape reads. The CPU runs take minutes at 100,000
spheres (Warp's CPU device runs one thread).
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import time
import traceback
from pathlib import Path

import numpy as np

import ndpack as nd
from ndpack.backends.prototypes import SPREAD_MAX
from ndpack.backends.warp_lanes import CONVERGE_MOST, COOPERATIVE_MOST, LANES

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cooperative_walk
from _common import machine_info, write_json
from profile_kernels import install_stages, launch_kind

#: Slots at the end of the instrumented shape's numbers: the nodes, evaluations and cooperative
#: rounds counters, then three per prototype of a converge launch.
COUNTERS = 3



# ------------------------------------------------------------------------------------ launches
class LaunchCounter:
    """Counts the device adapter's launches and synchronisations, per round."""

    def __init__(self):
        self.kernels = collections.defaultdict(lambda: [0, 0, 0])  # launches, threads, most threads
        self.syncs = 0
        self.sync_sites = collections.Counter()  # the store's method that waited, and the driver's that asked
        self.rounds = []  # per round: {"launches", "syncs", "move_threads"}
        self._mark = (0, 0, 0)

    def synchronised(self):
        """Count a synchronisation, by the store's method that made it and the driver's method that called that."""
        self.syncs += 1
        frames = [frame for frame in traceback.extract_stack()[:-2] if "ndpack" in frame.filename]
        store = [frame.name for frame in frames if frame.filename.endswith("prototypes.py")]
        driver = [frame.name for frame in frames if "drivers" in frame.filename]
        self.sync_sites[f"{store[0] if store else '-'} (from {driver[-1] if driver else '-'})"] += 1

    def launch(self, name, threads, args):
        entry = self.kernels[launch_kind(name, args)]
        entry[0] += 1
        entry[1] += threads
        entry[2] = max(entry[2], threads)

    def round_done(self):
        launches = sum(entry[0] for entry in self.kernels.values())
        moves = sum(entry[1] for name, entry in self.kernels.items() if name.startswith("move_ids"))
        last = self._mark
        self.rounds.append(dict(launches=launches - last[0], syncs=self.syncs - last[1], move_threads=moves - last[2]))
        self._mark = (launches, self.syncs, moves)


def _in_rounds() -> bool:
    """Whether the driver's rounds (``_run_rounds``) are on the call stack."""
    frame = sys._getframe(1)
    while frame is not None:
        if frame.f_code.co_name == "_run_rounds":
            return True
        frame = frame.f_back
    return False


def count_launches(shape, count, seed):
    """Pack on Warp's CPU device with the launches and synchronisations counted, and the host's
    own time in the rounds (their wall time less the launches', which Warp's CPU device runs to the
    end before returning): the Python and NumPy work a GPU run does between its launches."""
    from ndpack.backends import warp_backend
    from ndpack.drivers.greedy.centre_distances import CentreDistances

    counter = LaunchCounter()
    adapter = warp_backend._WarpDevice
    saved = adapter.launch, adapter.fetch, adapter.synchronize, CentreDistances.catch_up
    launch_seconds = [0.0]  # the launches' within the rounds (the set-up converges through the adapter too)
    check_seconds = [0.0]  # the final check's distances computed in the rounds, while a GPU moves

    def catch_up(self, *args, **kwargs):
        started = time.perf_counter()
        try:
            return saved[3](self, *args, **kwargs)
        finally:
            if _in_rounds():
                check_seconds[0] += time.perf_counter() - started

    def launch(self, name, threads, *args, **options):  # options: lanes, most
        if threads:
            counter.launch(name, threads, args)
        started = time.perf_counter()
        try:
            return saved[0](self, name, threads, *args, **options)
        finally:
            if _in_rounds():
                launch_seconds[0] += time.perf_counter() - started

    def fetch(self, *pairs):
        counter.synchronised()
        return saved[1](self, *pairs)

    def synchronize(self):
        counter.synchronised()
        return saved[2](self)

    adapter.launch, adapter.fetch, adapter.synchronize = launch, fetch, synchronize
    CentreDistances.catch_up = catch_up
    stages = {}
    try:
        backend = nd.backends.get_backend("warp", device="cpu")
        backend.launch_bound, backend.move_spread = True, SPREAD_MAX  # the GPU's policies (see gpu_policy)
        nd.pack(shape, 200, mode="fast", backend=backend, progress=False)  # compile
        counter.__init__()
        launch_seconds[0] = check_seconds[0] = 0.0
        undo = install_stages(stages)
        started = time.perf_counter()
        try:
            packing = nd.pack(shape, count, mode="fast", backend=backend, seed=seed, progress=False,
                              on_round=lambda _: counter.round_done())
        finally:
            undo()
        seconds = time.perf_counter() - started
    finally:
        adapter.launch, adapter.fetch, adapter.synchronize, CentreDistances.catch_up = saved
    kernels = {name: dict(launches=v[0], threads=v[1], most_threads=v[2])
               for name, v in sorted(counter.kernels.items())}
    return dict(backend="warp, cpu", seconds=seconds, spheres=len(packing), fill=float(packing.fill),
                rounds=len(counter.rounds), launches=sum(v["launches"] for v in kernels.values()),
                syncs=counter.syncs, syncs_by_method=dict(counter.sync_sites.most_common()),
                # The final check's distances, which a GPU computes while its moves run: apart.
                host_rounds_s=stages["rounds"][0] - launch_seconds[0] - check_seconds[0],
                check_in_rounds_s=check_seconds[0],
                verify_s=stages["verify"][0],
                split_ratio=packing.params.get("split_ratio"), kernels=kernels, per_round=counter.rounds)


# --------------------------------------------------------------------------------------- walks
def counting_nodes(text: str) -> str:
    """The shape's program text with a counter of the mesh-tree nodes its walks visit (the last
    slot of ``prm``): the nearest element's walk, and any other walk of the tree (a winding number's)."""
    nodes = "node = pending[top]\n"
    assert nodes in text, "nearest_element's walk is not where this script expects it"
    start = "def nearest_element(q, prm, o, limit):\n"
    assert start in text, "nearest_element is not where this script expects it"
    text = text.replace(start, start + f"    prm[prm.shape[0] - 3] += lanes_walk(q, prm, o, limit, {LANES})[1]\n")
    return text.replace(nodes, nodes + "        prm[prm.shape[0] - 1] += 1.0\n")


def counting_prototypes(text: str) -> str:
    """The backend's kernel text with a counter of distance evaluations (the second-last slot of
    ``prm``), and a converge launch writing each prototype's three counts into the tail of ``prm``."""
    evaluation = "    feature = sd_feature(x, prm, hint, gap_min)\n"
    assert evaluation in text, "nearest_obstacle's evaluation is not where this script expects it"
    text = text.replace(evaluation, "    prm[prm.shape[0] - 2] += 1.0\n" + evaluation)
    call = ("        converge_one(i, 0, points, starts, tries, lower, upper, wall, prm, centers, radii, nbr, steps, h, "
            "out_points,\n                     out_clearance)\n")
    assert call in text, "converge_all is not where this script expects it"
    return cooperative_walk.WALK + text.replace(call, (
        "        nodes = prm[prm.shape[0] - 1]\n"
        "        evaluations = prm[prm.shape[0] - 2]\n"
        "        rounds = prm[prm.shape[0] - 3]\n" + call +
        "        prm[prm.shape[0] - 4 - 3 * i] = prm[prm.shape[0] - 1] - nodes\n"
        "        prm[prm.shape[0] - 5 - 3 * i] = prm[prm.shape[0] - 2] - evaluations\n"
        "        prm[prm.shape[0] - 6 - 3 * i] = prm[prm.shape[0] - 3] - rounds\n"))


#: The hard-first question (issue 48, eleventh step): in a move launch too large to be cooperative, the
#: hardest K prototypes in cooperative blocks and the rest serial; K as below. Optimistic: a cooperative
#: block costs its whole move's steps, not only its walks' rounds, and few blocks are resident at once. Built
#: at the twelfth step with a threshold on the cells' walls in place of K (7e5176d, kept aside), the move
#: launches took twice as long on an H100, where this model promised 0.24-0.82 of their critical path.
HARD_FIRST = (256, 1024, 4096)
#: A cooperative walk's rounds against a serial walk's nodes, at the armadillo's worst point
#: (bench/cooperative_walk.py: 1,273 nodes in 47 rounds).
NODES_PER_ROUND = 1273 / 47


def hard_first(nodes, wall, ks=HARD_FIRST) -> dict:
    """A launch's critical path (nodes) if its K hardest prototypes walked cooperatively, for each K of
    ``ks``: chosen knowing their walks (``oracle_K``), or as those of the shallowest cells (``shallowest_K``:
    the smallest ``wall``, known before the move: the longest walks start in cells whose centres lie near
    the surface or outside it); ``nodes`` and ``wall`` (n,) per prototype of the launch."""
    nodes = np.asarray(nodes)
    found = {}
    for rule, order in (("oracle", np.argsort(-nodes, kind="stable")),
                        ("shallowest", np.argsort(np.asarray(wall)[:len(nodes)], kind="stable"))):
        for k in ks:
            rest = np.ones(len(nodes), bool)
            rest[order[:k]] = False
            found[f"{rule}_{k}"] = float(max(nodes[rest].max(initial=0), nodes[order[:k]].max(initial=0)
                                             / NODES_PER_ROUND))
    return found


def count_walks(shape, count, seed, most_points):
    """Pack on numba (one thread) with the converge kernel counting its tree walks."""
    from ndpack.backends import numba_backend, numba_common
    from ndpack.kernels import compile as kernel_compile
    from ndpack.kernels.compiled import compiled_program

    flat = compiled_program(shape)
    program = flat.program
    source = program.source
    program.source = lambda target, *rest: (counting_nodes(source(target, *rest)) if target == "numba"
                                            else source(target, *rest))
    text = counting_prototypes(numba_common.KERNELS + numba_common.ENTRIES)
    namespace = kernel_compile.numba_namespace(program, "cpu", text, numba_common._jit)
    program.source = source
    params = np.concatenate([flat.params, np.zeros(COUNTERS + 3 * most_points)])
    launches = []
    backend = numba_backend.NumbaBackend(threads=1)
    backend.launch_bound = True  # the GPU's rounds: polishes ahead (its two launches are one on a GPU)
    original_kernels, original_run = backend._kernels, backend._run

    def kernels(shape_):
        _, _, h = original_kernels(shape_)
        return namespace, params, h

    def run(namespace_, name, units, *args):
        result = original_run(namespace_, name, units, *args)
        if name == "converge_all" and namespace_ is namespace:
            points = len(args[0])
            if points > most_points:
                raise RuntimeError(f"a converge launch of {points:,} prototypes: pass --most-points above it")
            tail = params[len(params) - COUNTERS - 3 * points:len(params) - COUNTERS][::-1]
            nodes, evaluations, rounds = tail[0::3], tail[1::3], tail[2::3]
            # A GPU walks cooperatively in a move launch of few prototypes, and in the set-up's converge
            # (the first with steps) of a few more (ndpack.backends.warp_lanes).
            setup = not any(launch["steps"] for launch in launches) and len(args[10]) > 0
            cooperative = points <= (CONVERGE_MOST if setup else COOPERATIVE_MOST)
            launches.append(dict(prototypes=points, steps=len(args[10]), nodes=float(nodes.sum()),
                                 most_nodes=float(nodes.max(initial=0)), most_rounds=float(rounds.max(initial=0)),
                                 cooperative=bool(cooperative), evaluations=float(evaluations.sum()),
                                 most_evaluations=float(evaluations.max(initial=0)),
                                 hard_first=None if cooperative else hard_first(nodes, args[5])))
        return result

    backend._kernels, backend._run = kernels, run
    started = time.perf_counter()
    packing = nd.pack(shape, count, mode="fast", backend=backend, seed=seed, progress=False)
    seconds = time.perf_counter() - started
    plain = [launch for launch in launches if launch["hard_first"] is not None]
    hard = {f"{rule}_{k}": sum(launch["hard_first"][f"{rule}_{k}"] for launch in plain)
            / max(sum(launch["most_nodes"] for launch in plain), 1e-300)
            for rule in ("oracle", "shallowest") for k in HARD_FIRST}
    nodes = sum(launch["nodes"] for launch in launches)
    critical = sum(launch["most_nodes"] for launch in launches)
    serial = sum(launch["most_nodes"] for launch in launches if not launch["cooperative"])
    rounds = sum(launch["most_rounds"] for launch in launches if launch["cooperative"])
    prototypes = sum(launch["prototypes"] for launch in launches)
    return dict(backend="numba, 1 thread, instrumented", seconds=seconds, spheres=len(packing),
                fill=float(packing.fill), converge_launches=len(launches), prototypes_moved=prototypes,
                nodes=nodes, evaluations=sum(launch["evaluations"] for launch in launches),
                critical_path_nodes=critical, mean_path_nodes=nodes / max(prototypes, 1),
                serial_critical_nodes=serial, cooperative_critical_rounds=rounds,
                plain_launches=len(plain), hard_first=hard,
                critical_over_mean=critical / max(sum(launch["nodes"] / max(launch["prototypes"], 1)
                                                      for launch in launches), 1e-300),
                launches=launches)


def against(result: dict, profile: dict) -> dict:
    """The counts beside a GPU run of the same packing (``bench/profile_kernels.py``'s JSON, one
    backend): launches per kernel on both, and what the GPU's times imply per unit of counted work,
    the constants a prediction uses: a move launch's seconds per node of its critical path (with
    cooperative moves, from the run's ``lanes-off`` variant, and a cooperative round's from the rest), the
    other launches' seconds each, and, where the GPU run timed its stages (``--stages``), the
    host's time in the rounds and the final check over this machine's (the same Python and NumPy
    work on another CPU, with the synchronisations' latency), and the set-up's seconds. Without
    stages, the host's time over the synchronisations (the first model's, which did not hold)."""
    gpu = next(iter(profile.values()))
    counted = result["launches"]["kernels"]
    # A move launch's kind, cooperative or not (profile_kernels marks the former " lanes"): the CPU counts
    # them by kind alone.
    by_kind = collections.defaultdict(lambda: [0, 0.0])
    for name, entry in gpu["kernels"].items():
        by_kind[name.removesuffix(" lanes")][0] += entry[0]
        by_kind[name.removesuffix(" lanes")][1] += entry[1]
    rows = [dict(kernel=name, cpu_launches=counted.get(name, {}).get("launches", 0), gpu_launches=entry[0],
                 gpu_seconds=entry[1]) for name, entry in sorted(by_kind.items(), key=lambda item: -item[1][1])]
    moves = sum(entry[1] for name, entry in gpu["kernels"].items() if name.startswith("move_ids"))
    others = sum(entry[1] for name, entry in gpu["kernels"].items() if not name.startswith("move_ids"))
    other_launches = sum(entry[0] for name, entry in gpu["kernels"].items() if not name.startswith("move_ids"))
    host = gpu["median"] - gpu["device"]
    walks = result["walks"]
    found = dict(rows=rows, same_launches=all(row["cpu_launches"] == row["gpu_launches"] for row in rows),
                 gpu_median_s=gpu["median"], gpu_device_s=gpu["device"], gpu_move_s=moves, gpu_other_s=others,
                 seconds_per_critical_node=moves / walks["critical_path_nodes"],
                 seconds_per_other_launch=others / other_launches,
                 host_seconds_per_sync=host / result["launches"]["syncs"])
    serial = profile.get("warp lanes-off")
    if serial is not None and walks.get("cooperative_critical_rounds"):
        # Cooperative moves: a serial node's seconds from the run without them, a round's from the rest.
        per_node = sum(entry[1] for name, entry in serial["kernels"].items() if name.startswith("move_ids")) \
            / walks["critical_path_nodes"]
        found.update(seconds_per_critical_node=per_node, seconds_per_critical_round=(
            moves - per_node * walks["serial_critical_nodes"]) / walks["cooperative_critical_rounds"])
    stages = gpu.get("stages")
    if stages and "host_rounds_s" in result["launches"]:
        found.update(gpu_stages=stages, gpu_host_rounds_s=stages["rounds"] - gpu["device"],
                     host_over_cpu=(stages["rounds"] - gpu["device"]) / result["launches"]["host_rounds_s"],
                     verify_over_cpu=stages["verify"] / result["launches"]["verify_s"], setup_s=stages["setup"])
    return found


def predict(result: dict, constants: dict) -> dict:
    """The GPU's seconds for ``result``'s counts, by the constants another run's ``against`` gave:
    moves by their critical-path nodes (cooperative ones by their rounds, where the constants have
    them), other launches by their number, the host's rounds and
    the final check by this machine's times of them (scaled), the set-up as measured; with an
    older run's constants (no stages), the host by its synchronisations."""
    counted, walks = result["launches"], result["walks"]
    moves = sum(entry["launches"] for name, entry in counted["kernels"].items() if name.startswith("move_ids"))
    parts = dict(moves=walks["critical_path_nodes"] * constants["seconds_per_critical_node"],
                 other_launches=(counted["launches"] - moves) * constants["seconds_per_other_launch"])
    if "seconds_per_critical_round" in constants:  # cooperative moves: their rounds, the rest's nodes
        parts["moves"] = (walks["serial_critical_nodes"] * constants["seconds_per_critical_node"]
                          + walks["cooperative_critical_rounds"] * constants["seconds_per_critical_round"])
    if "host_over_cpu" in constants and "host_rounds_s" in counted:
        parts.update(host=counted["host_rounds_s"] * constants["host_over_cpu"],
                     verify=counted["verify_s"] * constants["verify_over_cpu"], setup=constants["setup_s"])
    else:
        parts["host"] = counted["syncs"] * constants["host_seconds_per_sync"]
    return dict(parts, seconds=sum(parts.values()))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", help="a mesh file (else the unit cube)")
    parser.add_argument("--count", type=int, default=100_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--parts", nargs="+", default=["launches", "walks"], choices=["launches", "walks"])
    parser.add_argument("--most-points", type=int, default=2_000_000, help="room for a converge launch's counts")
    parser.add_argument("--against", type=Path, help="a GPU run's bench/profile_kernels.py JSON, same packing")
    parser.add_argument("--constants", type=Path, help="an earlier work model JSON: its constants predict this run")
    parser.add_argument("--split-ratio", type=float,
                        help="the GPU's split ratio (rounds.SPLIT_RATIO_AHEAD) for both runs: a variant")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    if args.split_ratio is not None:
        from ndpack.drivers.greedy import rounds

        rounds.SPLIT_RATIO_AHEAD = args.split_ratio
    shape = nd.TriangleMesh.load(args.mesh) if args.mesh else nd.Box(np.zeros(3), np.ones(3))
    if args.constants:  # checked before the long runs
        constants = json.loads(args.constants.read_text())["against"]
    result = dict(machine=machine_info(), shape=args.mesh or "unit cube", count=args.count, seed=args.seed,
                  command="python bench/work_model.py " + " ".join(sys.argv[1:]))
    if "launches" in args.parts:
        result["launches"] = found = count_launches(shape, args.count, args.seed)
        print(f"device store (Warp CPU): {found['rounds']} rounds, {found['launches']:,} launches, "
              f"{found['syncs']:,} synchronisations, {found['seconds']:.1f} s; host in the rounds "
              f"{found['host_rounds_s']:.2f} s, final check {found['verify_s']:.2f} s; fill {found['fill']:.5f}")
        for name, entry in found["kernels"].items():
            print(f"  {name:24s} {entry['launches']:6,} launches, {entry['threads'] / entry['launches']:10,.0f} "
                  f"threads a launch (most {entry['most_threads']:,})")
        print("  synchronisations by the store's method (and the driver's that called it): " + ", ".join(
            f"{site} {n:,}" for site, n in found["syncs_by_method"].items()))
    if "walks" in args.parts:
        result["walks"] = found = count_walks(shape, args.count, args.seed, args.most_points)
        print(f"converge walks (numba, 1 thread): {found['converge_launches']} launches, "
              f"{found['prototypes_moved']:,.0f} prototypes moved, {found['nodes']:,.0f} tree nodes, "
              f"{found['evaluations']:,.0f} distance evaluations; a launch's slowest prototype summed over "
              f"launches: {found['critical_path_nodes']:,.0f} nodes, {found['critical_over_mean']:.1f}x the "
              f"mean prototype's ({found['seconds']:.1f} s); cooperative on a GPU: "
              f"{found['cooperative_critical_rounds']:,.0f} rounds, and {found['serial_critical_nodes']:,.0f} nodes "
              "in the other launches")
        print(f"  in the {found['plain_launches']} launches too large to be cooperative, their critical path with the "
              "K hardest cooperative, knowing the walks / the shallowest cells: " + ", ".join(
                  f"K={k}: {found['hard_first'][f'oracle_{k}']:.2f} / {found['hard_first'][f'shallowest_{k}']:.2f}"
                  for k in HARD_FIRST))
    if args.against and "launches" in result and "walks" in result:
        result["against"] = found = against(result, json.loads(args.against.read_text()))
        print(f"against {args.against.name}: same launches per kernel: {found['same_launches']}; the GPU's "
              f"{found['gpu_median_s']:.2f} s = {found['gpu_move_s']:.2f} s of moves "
              f"({1e6 * found['seconds_per_critical_node']:.2f} us a critical-path node) + "
              f"{found['gpu_other_s']:.2f} s of other launches ({1e3 * found['seconds_per_other_launch']:.3f} ms each) "
              f"+ {found['gpu_median_s'] - found['gpu_device_s']:.2f} s on the host "
              f"({1e3 * found['host_seconds_per_sync']:.2f} ms a synchronisation)")
        if "gpu_stages" in found:
            print("  stages on the GPU: " + ", ".join(f"{k} {v:.2f} s" for k, v in found["gpu_stages"].items())
                  + f"; the host's rounds {found['host_over_cpu']:.2f}x and the final check "
                  f"{found['verify_over_cpu']:.2f}x this machine's")
    if args.constants and "launches" in result and "walks" in result:
        result["prediction"] = found = predict(result, constants)
        found["constants_from"] = args.constants.name
        measured = result.get("against", {}).get("gpu_median_s")
        print(f"predicted by {args.constants.name}'s constants: {found['seconds']:.2f} s ("
              + ", ".join(f"{k} {v:.2f} s" for k, v in found.items() if k not in ("seconds", "constants_from"))
              + ")" + (f"; the GPU took {measured:.2f} s" if measured else ""))
    if args.out:
        write_json(args.out, result)


if __name__ == "__main__":
    main()
