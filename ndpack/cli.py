"""The ``ndpack`` command line. ``ndpack pack --help`` lists the options."""

from __future__ import annotations

import argparse
import sys
import time

from .errors import NdpackError

EXAMPLES = """examples:
  ndpack pack                          # the 3-D demo part, 1000 spheres
  ndpack pack box:dim=4 -n 500 -o box4.npz
  ndpack pack ball --dim 6 -n 200
  ndpack pack annulus -n 2000 --batch 8 -o ring.csv
  ndpack pack box:dim=3 -n 100000 --mode fast -o cube.npz
built-in shapes: {shapes}
"""


def _parser() -> argparse.ArgumentParser:
    from .builtin import BUILTIN

    parser = argparse.ArgumentParser(prog="ndpack", description="Pack spheres into shapes.")
    commands = parser.add_subparsers(dest="command", required=True)
    pack = commands.add_parser(
        "pack",
        help="pack a built-in shape and print a summary",
        epilog=EXAMPLES.format(shapes=", ".join(BUILTIN)),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    pack.add_argument("shape", nargs="?", default="demo", help="shape spec name[:key=value,...] (default: demo)")
    pack.add_argument("--dim", type=int, help="dimension of the built-in shape (same as :dim=)")
    pack.add_argument("-n", "--count", type=int, default=1000, help="number of spheres (default 1000)")
    pack.add_argument("-o", "--output", help="write the packing to this .npz or .csv file")
    pack.add_argument("--min-radius", type=float, default=0.0, help="stop below this radius")
    pack.add_argument("--fill", type=float, help="stop at this fill fraction")
    pack.add_argument("--time", type=float, dest="time_budget", help="stop after this many seconds")
    pack.add_argument("--grid", type=int, help="grid cells along the longest side")
    pack.add_argument("--iterations", type=int, default=50, help="prototype steps (default 50)")
    pack.add_argument("--batch", type=int, default=1, help="spheres per round in the faithful mode (default 1)")
    pack.add_argument("--mode", choices=("faithful", "fast"), default="faithful",
                      help="faithful: the paper's rounds (default); fast: many spheres a round and a "
                      "grid refined where gaps are small, for large counts")
    pack.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    pack.add_argument("--backend", help="numpy, numba, numba-cuda or warp (default: $NDPACK_BACKEND or the fastest)")
    pack.add_argument("--device", help="cpu or cuda:N, for warp and numba-cuda")
    pack.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    return parser


def _pack(args) -> int:
    from .builtin import from_spec
    from .protosphere import pack

    spec = args.shape
    if args.dim is not None:
        spec += ("," if ":" in spec else ":") + f"dim={args.dim}"
    shape = from_spec(spec)
    started = time.perf_counter()
    packing = pack(
        shape,
        n=args.count,
        min_radius=args.min_radius,
        fill=args.fill,
        time_budget=args.time_budget,
        grid=args.grid,
        iterations=args.iterations,
        batch=args.batch,
        mode=args.mode,
        seed=args.seed,
        backend=args.backend,
        device=args.device,
        progress=not args.quiet and sys.stderr.isatty(),
    )
    elapsed = time.perf_counter() - started
    report = packing.verify()
    print(f"shape:    {args.shape} -> {shape!r}")
    print(f"spheres:  {len(packing)} (stopped by {packing.stop_reason})")
    error = f" +- {packing.fill_error:.4f}" if packing.volume_error else ""
    print(f"fill:     {packing.fill:.4f}{error}")
    print(f"time:     {elapsed:.2f} s ({packing.params['backend']} backend)")
    print(f"verified: {report.summary()}")
    if args.output:
        print(f"saved:    {packing.save(args.output)}")
    return 0 if report.ok else 1


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    try:
        return {"pack": _pack}[args.command](args)
    except NdpackError as error:
        print(f"ndpack: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("ndpack: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
