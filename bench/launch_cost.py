"""What a Warp launch costs the host: a plain ``wp.launch`` against a replay of its recorded launch.

    python bench/launch_cost.py --out bench/results/launch_cost_2core.json

The device store's launches (:class:`ndpack.backends.warp_backend._WarpDevice`) replay a recorded
``wp.Launch`` per kernel and set again only the arguments that changed. Here an empty kernel with a
move launch's 22 arguments (arrays and scalars of its types) is launched ``--count`` times each way,
on Warp's CPU device (the host's share is the same on a GPU): plainly, and as a replay that sets two
arrays, a scalar and the launch's size each time, as a round's launches do. Median of ``--repeats``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import warp as wp

from _common import machine_info, write_json

wp.config.quiet = True

V = wp.vec3d
F = wp.float64


@wp.kernel
def move_shaped(ids: wp.array(dtype=wp.int32), first: wp.array(dtype=V), first_rows: int, tries: int,
                stream: wp.uint64, points: wp.array(dtype=V), clearance: wp.array(dtype=F),
                polished: wp.array(dtype=wp.int32), lower: wp.array(dtype=V), upper: wp.array(dtype=V),
                wall: wp.array(dtype=F), prm: wp.array(dtype=F), centers: wp.array(dtype=V), radii: wp.array(dtype=F),
                nbr: wp.array2d(dtype=wp.int32), steps: wp.array(dtype=F), h: F, polish: int, spread: int,
                polish_steps: wp.array(dtype=F), polish_low: F, polish_from: int):
    wp.tid()  # the launch's cost, not the kernel's


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    device = "cpu"

    def array(dtype, shape=8):
        return wp.zeros(shape, dtype=dtype, device=device)

    ids = [array(wp.int32) for _ in range(2)]
    inputs = [ids[0], array(V), 0, 8, wp.uint64(7), array(V), array(F), array(wp.int32), array(V), array(V),
              array(F), array(F), array(V), array(F), array(wp.int32, (8, 2)), array(F), 1e-6, 0, 32, array(F),
              0.5, 8]
    wp.launch(move_shaped, dim=1, inputs=inputs, device=device)  # compile
    plain, replayed = [], []
    for _ in range(args.repeats):
        started = time.perf_counter()
        for k in range(args.count):
            inputs[0] = ids[k % 2]
            wp.launch(move_shaped, dim=1 + k % 3, inputs=inputs, device=device)
        plain.append((time.perf_counter() - started) / args.count)
        command = wp.launch(move_shaped, dim=1, inputs=inputs, device=device, record_cmd=True)
        started = time.perf_counter()
        for k in range(args.count):
            command.set_param_at_index(0, ids[k % 2])
            command.set_param_at_index(6, inputs[6])
            command.set_param_at_index(20, 0.5 + k)
            command.set_dim(1 + k % 3)
            command.launch()
        replayed.append((time.perf_counter() - started) / args.count)
    row = dict(arguments=len(inputs), plain_us=1e6 * statistics.median(plain),
               replay_us=1e6 * statistics.median(replayed), count=args.count, repeats=args.repeats)
    print(f"a launch of {row['arguments']} arguments: plain {row['plain_us']:.1f} us, "
          f"replayed setting 3 and the size {row['replay_us']:.1f} us (median of {args.repeats})")
    if args.out:
        write_json(args.out, dict(machine=machine_info(), command="python bench/launch_cost.py", rows=[row]))


if __name__ == "__main__":
    main()
