"""The ``ndpack`` command line: ``pack``, ``cover``, ``verify``, ``render``, ``info`` and ``backends``.

Every mistake in the input ends in one line on stderr and a non-zero exit: 2 for bad input,
1 for a packing that fails verification (or a covering that leaves samples or links uncovered),
130 for an interrupted run (after saving what it made).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
import tempfile
import time
import warnings
from pathlib import Path

from .errors import KEPT_IN_ERROR, InvalidPackingError, NdpackError, ParameterError

PACK_EXAMPLES = """examples:
  ndpack pack                                   # the 3-D demo part, 1000 spheres
  ndpack pack box:dim=4 -n 500 -o box4.npz      # a built-in shape, any dimension
  ndpack pack cow.obj -n 5000 -o cow.npz
  ndpack pack part.py -n 2000 -o part.vtp       # a script that sets `shape` (ndpack or manifold3d)
  ndpack pack my_shapes:gyroid -n 1000          # a plug-in: module:function
  ndpack pack annulus -n 2000 --batch 8 -o ring.csv
  ndpack pack box:dim=3 -n 100000 --backend warp --device cuda:0 -o cube.npz
  ndpack pack cow.obj -n 3000 -o cow.json --format curobo --option link=cow
  ndpack pack parts/*.stl -n 5000 -o out/       # many parts, on every core: out/<part>.npz, out/manifest.json
  ndpack pack box:dim=3 -n 2000000 --tiles auto -o big.npz   # one domain in tiles, on every core

SHAPE is a built-in name[:key=value,...], a mesh file (.obj .stl .ply .off .glb ...), a Python
script (.py) that sets `shape`, or module:function. Built-in shapes: {shapes}.
Several shapes (or a folder, for the mesh files in it, or a pattern such as 'parts/*.stl') are
packed at once (--workers), each to -o FOLDER/<name>.npz (or --format), with FOLDER/manifest.json;
run again, the parts already made are skipped. Exit 1 if a part failed (the others are written).
Ctrl-C stops the run and still writes what was packed to --output. An output that cannot be
written is refused before packing; a save that fails later (a full disk) keeps the packing as
.npz beside it, in the current folder or in the temporary folder, and the error says where.

output formats (by suffix, or --format):
{formats}
"""

COVER_EXAMPLES = """examples:
  ndpack cover part.obj -n 32 -o part.sph                # at most 32 spheres, protruding as little as can be
  ndpack cover part.obj --protrusion 0.01 -o part.json   # out by at most 1% of the bounding-box diagonal
  ndpack cover part.stl --protrusion-abs 0.002 -o part.yml --option link=gripper   # cuRobo YAML, 2 mm out
  ndpack cover box:dim=3 -n 8                            # any shape `ndpack pack` takes; report only
  ndpack cover robot.urdf -n 32 -o robot_spheres/        # each link of a robot: URDF, cuRobo YAML, report
  ndpack cover robot.urdf --protrusion 0.02 -o out/ --package my_robot=$HOME/ws/src/my_robot

The spheres' union covers the shape (checked on fresh samples of its boundary and inside), and
each sphere reaches outside it by at most the protrusion. SHAPE is what `ndpack pack` takes (a
built-in name[:key=value,...], a mesh file, a .py script, module:function) or a .urdf file.
For a URDF, -o names a folder; it receives <robot>_spheres.urdf (each covered link's collision
elements replaced by its spheres, in the link's frame), <robot>_spheres.yml (cuRobo's
collision_spheres) and report.json; -n and --protrusion then apply to each link on its own, and
a link whose mesh is missing or broken is reported and keeps its collision elements.
exit status: 0 all covered, 1 some samples (or links) not covered, 2 bad input.

output formats (by suffix, or --format; .yml and .yaml are cuRobo YAML):
{formats}
"""

VERIFY_EXAMPLES = """examples:
  ndpack verify cow.npz                         # the shape recorded in the file
  ndpack verify spheres.csv --shape part.stl    # a packing made elsewhere, against a mesh
  ndpack verify part.npz --shape part.py        # a script's shape: named by you, not the file
exit status: 0 valid, 1 a violation, 2 bad input.

A file's recorded shape is used only where it is data (a mesh file or a built-in shape):
a packing file may come from anyone, and one naming a script or module is never run unless
you pass --shape or --trust-source. A recorded mesh is reloaded with the --holes choice the
file records (an open mesh packed with its holes capped is checked capped) unless you pass one.
"""

RENDER_EXAMPLES = """examples:
  ndpack render cow.npz -o cow.png              # 3-D: a shaded picture, standing up
  ndpack render cow.npz -o cow.png --view -35,20          # the camera at azimuth -35, 20 degrees up
  ndpack render scan.npz -o scan.png --up y     # stand y up (auto: the mesh file's convention, ...)
  ndpack render cow.npz -o cut.png --clip 0,0,0,1,0,0     # drop the spheres beyond x = 0
  ndpack render ring.npz -o ring.svg            # 2-D: circles with the outline
  ndpack render box4.npz -o slice.png --kind slice --axes 0,1 --at 0.5,0.5,0.5,0.5
  ndpack render cube.npz -o fill.png --kind fill
"""

INFO_EXAMPLES = """examples:
  ndpack info cow.npz
"""


def _numbers(text: str) -> tuple:
    try:
        values = tuple(float(x) for x in text.split(","))
    except ValueError:
        values = (math.nan,)
    if not all(math.isfinite(value) for value in values):
        raise argparse.ArgumentTypeError(f"expected comma-separated finite numbers, got {text!r}")
    return values


def _periodic_axes(text: str):
    """``--periodic``: ``all`` or axis numbers, ``0,2``."""
    if text.strip().lower() == "all":
        return "all"
    try:
        return tuple(int(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'all' or axis numbers such as 0,1, got {text!r}") from None


def _integer_from(least: int):
    """An argparse type: an integer of at least ``least``."""
    def parse(text: str) -> int:
        if not text.strip().isdigit() or int(text) < least:
            raise argparse.ArgumentTypeError(f"expected an integer >= {least}, got {text!r}")
        return int(text)

    return parse


def _finite(text: str, positive: bool = False) -> float:
    """A finite number >= 0 (> 0 where ``positive``)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and (value > 0 if positive else value >= 0)):
        raise argparse.ArgumentTypeError(f"expected a finite number {'>' if positive else '>='} 0, got {text!r}")
    return value


_seed, _positive_int = _integer_from(0), _integer_from(1)
_nonnegative = _finite


def _positive_float(text: str) -> float:
    return _finite(text, positive=True)


def _integers(text: str) -> tuple:
    try:
        return tuple(int(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None


def _size(text: str) -> tuple:
    width, x, height = text.lower().partition("x")
    try:
        size = int(width), int(height)
    except ValueError:
        size = (0, 0)
    if min(size) < 1:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels such as 900x900, got {text!r}")
    return size


def _option(text: str) -> tuple:
    """``KEY=VALUE`` -> ``(key, value)``, the value an int where it reads as one."""
    key, equals, value = text.partition("=")
    if not equals or not key:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    return key.strip(), int(value) if value.strip().lstrip("-").isdigit() else value


#: The help of --holes, which pack, verify and render share.
HOLES_HELP = ("an open mesh file: cap closes each hole with a fan of triangles (the default, with a warning), "
              "refuse exits")
HOLES_REUSE = "; default: what the packing records"
HOLE_CHOICES = ("cap", "refuse")
#: The help of --sign, which pack, cover, verify and render share.
SIGN_HELP = ("a mesh file: how inside is told; auto (the default) takes pseudo-normals, or the winding number "
             "for a surface that crosses itself or is open (slower, and said in a note)")
SIGN_CHOICES = ("auto", "pseudonormal", "winding")


def _sizes(text: str):
    """``--sizes``: ``radius:R`` (equal spheres), ``lognormal:median=M,sigma=S[,by=mass]`` or
    ``discrete:radii=R1/R2/...,shares=S1/S2/...[,by=mass]``: a radius or a SizeDistribution."""
    from .drivers.sizes import SizeDistribution

    kind, _, rest = text.partition(":")
    usage = ("give radius:R, lognormal:median=M,sigma=S[,by=mass] or discrete:radii=R1/R2,shares=S1/S2[,by=mass], "
             f"not {text!r}")
    try:
        if kind == "radius":
            radius = float(rest)
            if not (math.isfinite(radius) and radius > 0):
                raise ValueError(rest)
            return radius
        fields = dict(part.split("=", 1) for part in rest.split(",") if part)
        by = fields.pop("by", "count")
        if kind == "lognormal" and set(fields) == {"median", "sigma"}:
            return SizeDistribution.lognormal(float(fields["median"]), float(fields["sigma"]), by=by)
        if kind == "discrete" and set(fields) == {"radii", "shares"}:
            return SizeDistribution.discrete([float(v) for v in fields["radii"].split("/")],
                                             [float(v) for v in fields["shares"].split("/")], by=by)
    except (ValueError, NdpackError) as error:
        raise argparse.ArgumentTypeError(f"{usage} ({error})") from None
    raise argparse.ArgumentTypeError(usage)


def _fraction(text: str) -> float:
    """``--solid-fraction``: a share of the shape's volume, 0 < share < 1."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0 < value < 1):
        raise argparse.ArgumentTypeError(f"expected a share of the volume between 0 and 1 (0.6), got {text!r}")
    return value


def _share(text: str) -> float:
    """``--protrusion``: a share of the diagonal, 0 < share < 1 (``1%`` is accepted too)."""
    percent = text.strip().endswith("%")
    try:
        value = float(text.strip().rstrip("%")) / (100 if percent else 1)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0 < value < 1):
        raise argparse.ArgumentTypeError(f"expected a share of the diagonal between 0 and 1 (0.01 or 1%), got "
                                         f"{text!r}; --protrusion-abs takes a length")
    return value


def _parser() -> argparse.ArgumentParser:
    from .io.named_shapes import BUILTIN
    from .drivers.collision.covering import CHECK_SAMPLES, DEFAULT_SAMPLES
    from .drivers.collision.estimate import MAX_SPHERES
    from .io import table
    from .pictures.view import UP_CHOICES
    from .drivers.greedy.protosphere import AUTO_FAST_ABOVE

    parser = argparse.ArgumentParser(
        prog="ndpack",
        description="Fill shapes, in any dimension, with non-overlapping spheres (ProtoSphere).",
        epilog="`ndpack COMMAND --help` shows each command's options and examples.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    raw = argparse.RawDescriptionHelpFormatter

    pack = commands.add_parser("pack", help="pack a shape and save the spheres", formatter_class=raw,
                               epilog=PACK_EXAMPLES.format(shapes=", ".join(BUILTIN), formats=table()))
    pack.add_argument("shape", nargs="*", default=["demo"],
                      help="built-in spec, mesh file, .py script or module:function (default: demo); several, "
                      "a folder of meshes or a glob pattern pack many parts, each to -o FOLDER/")
    pack.add_argument("--dim", type=int, help="dimension of a built-in shape (same as :dim=)")
    pack.add_argument("--holes", choices=HOLE_CHOICES, help=HOLES_HELP)
    pack.add_argument("--sign", choices=SIGN_CHOICES, help=SIGN_HELP)
    pack.add_argument("-n", "--count", type=int, default=1000, help="number of spheres (default 1000)")
    pack.add_argument("-o", "--output", help="write the packing here; the suffix picks the format")
    pack.add_argument("--format", help="the output format where the suffix does not say (e.g. curobo, medial)")
    pack.add_argument("--option", action="append", default=[], metavar="KEY=VALUE", type=_option,
                      help="a format option, repeatable: encoding=ascii, subdivisions=2, link=cow (see below)")
    pack.add_argument("--min-radius", type=float, default=0.0,
                      help="no sphere smaller than this: the run stops when none fits")
    pack.add_argument("--max-radius", type=float,
                      help="no sphere larger than this (equal to --min-radius: equal spheres)")
    pack.add_argument("--periodic", type=_periodic_axes, metavar="AXES",
                      help="make these axes of the shape's bounding box periodic: all, or numbers such as 0,1 "
                      "(a periodic box: box:dim=4 --periodic all)")
    pack.add_argument("--sizes", type=_sizes, metavar="SPEC",
                      help="radii from a size distribution (granular beds): radius:R (equal spheres), "
                      "lognormal:median=M,sigma=S[,by=mass] or discrete:radii=R1/R2,shares=S1/S2[,by=mass]; "
                      "-n of them, or as many as --solid-fraction asks (nd.pack_sizes; with --dense, nd.pack_dense)")
    pack.add_argument("--solid-fraction", type=_fraction, metavar="SHARE",
                      help="with --sizes: as many particles as fill this share of the shape's volume (instead of -n)")
    pack.add_argument("--dense", action="store_true",
                      help="with --sizes: a dense random bed, all particles jammed together (nd.pack_dense), "
                      "not placed one by one in the largest gaps")
    pack.add_argument("--centers-only", action="store_true",
                      help="only the centres must lie inside (needs --max-radius): spheres may reach past the "
                      "walls by their radius, as DEM codes cut a bed by centre")
    pack.add_argument("--fill", type=float, help="stop at this fill fraction")
    pack.add_argument("--time", type=float, dest="time_budget", help="stop after this many seconds")
    pack.add_argument("--grid", type=int, help="grid cells along the longest side")
    pack.add_argument("--iterations", type=int, default=50, help="prototype steps (default 50)")
    pack.add_argument("--batch", type=int, default=1, help="spheres per round in the faithful mode (default 1)")
    pack.add_argument("--mode", choices=("auto", "faithful", "fast"), default="auto",
                      help=f"auto (default): fast for more than {AUTO_FAST_ABOVE} spheres, else "
                      "faithful; faithful: the paper's rounds, one sphere each; fast: many spheres a round and a "
                      "grid refined where gaps are small, for large counts")
    pack.add_argument("--seed", type=_seed, default=0, help="random seed, an integer >= 0 (default 0)")
    pack.add_argument("--backend", help="numpy, numba, numba-cuda or warp (default: $NDPACK_BACKEND or the fastest)")
    pack.add_argument("--device", help="cpu or cuda:N, for warp and numba-cuda")
    pack.add_argument("--on-invalid", choices=("repair", "raise"),
                      help="should the final float64 check fail: repair (shrink or drop the spheres, and "
                      "say so; the default) or raise (exit 2, nothing saved)")
    pack.add_argument("--tiles", type=_tiles, metavar="auto|N|N,N,...",
                      help="pack one shape in tiles on --workers processes (ndpack.pack_tiled): a global phase "
                      "for the large spheres, then the tiles in bands of radius; auto: 4 slabs per worker "
                      "across the longest side, N: N tiles along each axis, N,N,...: per axis")
    pack.add_argument("--workers", type=_positive_int,
                      help="several shapes: parts packed at once, each in its own process; --tiles: the processes "
                      "that pack the tiles (default: all cores)")
    pack.add_argument("-q", "--quiet", action="store_true", help="no progress bar")

    cover = commands.add_parser("cover", help="cover a shape, or each link of a robot (URDF), with spheres",
                                formatter_class=raw, epilog=COVER_EXAMPLES.format(formats=table()))
    cover.add_argument("shape", help="built-in spec, mesh file, .py script, module:function, or a .urdf file")
    cover.add_argument("--dim", type=int, help="dimension of a built-in shape (same as :dim=)")
    cover.add_argument("--holes", choices=HOLE_CHOICES, help=HOLES_HELP + " (for a URDF: its meshes)")
    cover.add_argument("--sign", choices=SIGN_CHOICES, help=SIGN_HELP)
    how = cover.add_mutually_exclusive_group(required=True)
    how.add_argument("-n", "--count", type=_positive_int, help="at most this many spheres (per link for a URDF)")
    how.add_argument("--protrusion", type=_share, metavar="SHARE",
                     help="how far a sphere may reach outside the shape, as a SHARE of the shape's bounding-box "
                     "diagonal (of each link's, for a URDF): 0.01 is 1%%")
    how.add_argument("--protrusion-abs", type=_positive_float, metavar="LENGTH",
                     help="the same as a length, in the shape's units (metres for a URDF)")
    cover.add_argument("-o", "--output",
                       help="write the spheres here (the suffix picks the format); for a URDF, the output folder")
    cover.add_argument("--format", help="the output format where the suffix does not say (e.g. curobo for .json)")
    cover.add_argument("--option", action="append", default=[], metavar="KEY=VALUE", type=_option,
                       help="a format option, repeatable: link=gripper, subdivisions=2 (see below)")
    cover.add_argument("--package", action="append", default=[], metavar="NAME=FOLDER", type=_option,
                       help="a URDF: the folder of ROS package NAME, for package://NAME/... mesh names the search "
                       "does not find (repeatable)")
    cover.add_argument("--samples", type=_positive_int, default=DEFAULT_SAMPLES,
                       help=f"boundary samples the cover is made on (default {DEFAULT_SAMPLES})")
    cover.add_argument("--check-samples", type=_positive_int, default=CHECK_SAMPLES,
                       help=f"fresh boundary samples of the final check (default {CHECK_SAMPLES})")
    cover.add_argument("--max-spheres", type=_integer_from(0), default=MAX_SPHERES, metavar="N",
                       help=f"refuse, before any work, a protrusion estimated to need more spheres than this "
                       f"(default {MAX_SPHERES:,}; 0: no limit)")
    cover.add_argument("--seed", type=_seed, default=0, help="random seed, an integer >= 0 (default 0)")
    cover.add_argument("--backend", help="backend of the packing that finds the medial axis (default: the fastest)")
    cover.add_argument("--device", help="cpu or cuda:N, for warp and numba-cuda")
    cover.add_argument("-q", "--quiet", action="store_true", help="no progress bar")

    verify = commands.add_parser("verify", help="re-check a saved packing against its shape", formatter_class=raw,
                                 epilog=VERIFY_EXAMPLES)
    verify.add_argument("packing", help="a packing file (.npz, .csv, .json, ...)")
    verify.add_argument("--shape", help="the shape to check against (default: the one the file records)")
    verify.add_argument("--tol", type=_nonnegative, help="overlap and containment tolerance, >= 0 (default: ndpack's)")
    verify.add_argument("--holes", choices=HOLE_CHOICES, help=HOLES_HELP + HOLES_REUSE)
    verify.add_argument("--sign", choices=SIGN_CHOICES, help=SIGN_HELP + HOLES_REUSE)
    verify.add_argument("--independent", action="store_true",
                        help="a mesh: also check 48 points on each sphere by the exact winding number, summed "
                        "over every triangle (slow: points x triangles)")
    verify.add_argument("--trust-source", action="store_true",
                        help="run the script or module the file records as its shape (only for files you trust)")
    verify.add_argument("--as", dest="kind", choices=("packing", "centers-only", "covering"),
                        help="what to check, whatever the file says: packing (each sphere whole inside, no "
                        "overlap, no period but --periodic's), centers-only (the centres inside), covering (the "
                        "spheres cover the shape); default: what the file records, named in the verdict")
    verify.add_argument("--periodic", type=_periodic_axes, metavar="AXES",
                        help="the shape's bounding box is periodic along these axes: all, or numbers such as 0,1 "
                        "(default: the period the file records)")

    render = commands.add_parser("render", help="draw a saved packing to .png, .svg or .pdf", formatter_class=raw,
                                 epilog=RENDER_EXAMPLES,
                                 description="Draw a saved packing. Turn a 3-D picture with --up (which axis points "
                                 "up),\n--view AZIMUTH,ELEVATION (where the camera looks from) and --axes (which "
                                 "axes,\nin which order).")
    render.add_argument("packing", help="a packing file")
    render.add_argument("-o", "--output", help="the picture (default: the packing's name with .png)")
    render.add_argument("--kind", choices=("auto", "render", "slice", "fill"), default="auto",
                        help="auto: circles in 2-D, a shaded render in 3-D and up; slice: circles cut by a "
                        "plane; fill: fill against count")
    render.add_argument("--size", type=_size, help="WIDTHxHEIGHT of a shaded render (default 900x900)")
    render.add_argument("--up", choices=UP_CHOICES,
                        help="the axis that points up on screen (-y: y pointing down). auto "
                        "(default): the axis it stands on its broadest base along, with the centre of mass above "
                        "it (ties: the mesh file's convention, .obj/.gltf/.glb y, .stl/.3mf z); no base: the "
                        "convention, else a clearly longest extent, else z; a slice shows it vertical")
    render.add_argument("--view", type=_numbers, metavar="AZIMUTH,ELEVATION",
                        help="AZIMUTH,ELEVATION in degrees (default 35,25): the camera turns about the up axis, "
                        "and rises above the plane across it")
    render.add_argument("--axes", type=_integers,
                        help="the axes of the picture or slice, e.g. 0,1 or 0,1,2; given without --up, the last "
                        "points up (2,0,1 stands y up)")
    render.add_argument("--at", type=_numbers, help="a point of the slice (default: the centres' mean)")
    render.add_argument("--clip", type=_numbers, help="px,py,pz,nx,ny,nz: drop spheres beyond this plane")
    render.add_argument("--shape", help="the shape whose outline a slice draws (default: the recorded one)")
    render.add_argument("--holes", choices=HOLE_CHOICES, help=HOLES_HELP + HOLES_REUSE)
    render.add_argument("--sign", choices=SIGN_CHOICES, help=SIGN_HELP + HOLES_REUSE)
    render.add_argument("--trust-source", action="store_true",
                        help="run the script or module the file records as its shape (only for files you trust)")

    info = commands.add_parser("info", help="summarise a saved packing", formatter_class=raw, epilog=INFO_EXAMPLES)
    info.add_argument("packing", help="a packing file")

    commands.add_parser("backends", help="list the backends that work here, and why the others do not")

    samples = commands.add_parser("samples", help="write the sample files the docs use (cow.obj, arm.urdf, ...)",
                                  formatter_class=raw, epilog=SAMPLES_EXAMPLES)
    samples.add_argument("folder", nargs="?", default=".", help="where to write them (default: here)")
    samples.add_argument("--suffix", default=".obj", help="mesh format by suffix (default .obj; .stl, .ply, .glb, ...)")
    return parser


# ---------------------------------------------------------------------------------------- pack
#: What each ``stop_reason`` means, as ``ndpack pack`` prints it.
STOP_REASONS = {
    "count": "the count asked for", "fill": "the fill asked for reached", "time": "the time budget spent",
    "min_radius": "no sphere of the least radius fits", "no_room": "no room left",
    "callback": "stopped by the callback",
    "interrupted": "interrupted (Ctrl-C): what was packed so far",
    "jammed": "jammed: the densest random bed found", "fraction": "the solid fraction asked for reached",
    "relaxations": "the search's relaxations spent: the densest bed found",
}


def _plus_minus(error: float) -> str:
    """`` +- error`` with the digits it has (a Monte Carlo volume's standard error)."""
    return f" +- {error:.4f}" if error >= 5e-5 else f" +- {error:.1e}"


def _pack(args) -> int:
    from .packing import repair_summary
    from .drivers.greedy.protosphere import pack
    from .shapes.mesh import mesh_notes
    from .io.shape_sources import describe, load_shape

    shapes, many = _expand_shapes(args.shape)
    if many or len(shapes) > 1 or (args.output and _is_folder(args.output)):
        return _pack_many(args, shapes)
    args.shape = shapes[0]
    called = time.perf_counter()
    source = _with_dim(args.shape, args.dim)
    shape = load_shape(source, args.holes, args.sign)
    if args.periodic is not None:
        from .shapes.periodic import Periodic

        shape = Periodic(shape, None if args.periodic == "all" else args.periodic)
    options = dict(args.option)
    if args.output:
        _check_output(args.output, args.format, shape.dim, options)
    elif options or args.format:
        raise ParameterError("--format and --option describe the output file: give it with -o PATH")
    started = time.perf_counter()
    common = dict(n=args.count, min_radius=args.min_radius, grid=args.grid, iterations=args.iterations,
                  mode=args.mode, seed=args.seed, backend=args.backend, device=args.device,
                  progress=not args.quiet and sys.stderr.isatty(), on_invalid=args.on_invalid)
    if args.sizes is not None or args.dense or args.solid_fraction is not None:
        packing = _pack_sized(args, shape)
    elif args.tiles is not None:
        packing = _pack_keeping_invalid(_pack_tiled(args), args.output, shape, **common)
    else:
        packing = _pack_keeping_invalid(pack, args.output, shape, max_radius=args.max_radius, fill=args.fill,
                                        time_budget=args.time_budget, batch=args.batch,
                                        centers_only=args.centers_only, **common)
    elapsed = time.perf_counter() - started
    packing.params["source"] = describe(source)
    if args.sign is not None:  # verify and render reload the mesh the same way
        packing.params["sign"] = args.sign
    report = packing.verify()
    print(f"shape:    {source} -> {shape!r}")
    for note in mesh_notes(shape):
        print(f"note:     {note}")
    print(f"spheres:  {len(packing)} ({STOP_REASONS.get(packing.stop_reason, packing.stop_reason)})")
    if len(packing) == 1 and packing.stop_reason == "no_room":
        print(f"note:     one sphere fills the shape (a ball is its own largest sphere); for a packing, try a "
              f"ball with a hole: annulus:dim={shape.dim}")
    print(f"fill:     {packing.fill:.4f}{_plus_minus(packing.fill_error) if packing.volume_error else ''}")
    print(f"verified: {report.summary()}")
    if packing.params.get("mode") == "dense":
        contacts = packing.params["contacts"]
        print(f"contacts: {contacts['mean']:.2f} a particle ({contacts['backbone_mean']:.2f} among the "
              f"{len(packing) - contacts['rattlers']:,} that are not rattlers), {contacts['wall']:,} on walls; "
              f"radii {packing.params['scale']:.4g} x the sizes")
    tiled = packing.params.get("tiled")
    if tiled:
        print(f"tiles:    {' x '.join(map(str, tiled['tiles']))} on {tiled['workers']} workers; "
              f"{tiled['global_spheres']} spheres in the global phase ({tiled['global_seconds']:.2f} s), the rest in "
              f"{len(tiled['bands'])} bands ({tiled['phase_seconds']:.2f} s, workers busy {tiled['busy_share']:.0%})")
    if packing.repair:
        print(f"REPAIRED: {repair_summary(packing.repair)}")
    if args.output:
        print(f"saved:    {_save_or_keep(packing, args.output, args.format, options)}")
    else:
        print("saved:    nothing (give -o PATH to keep the spheres)")
    print(f"time:     {elapsed:.2f} s packing ({packing.params['backend']} backend, "
          f"{packing.params['mode']} mode), "
          f"{time.perf_counter() - called:.2f} s in all (loading, checking, saving)")
    if packing.stop_reason == "interrupted":
        print("ndpack: interrupted; " + ("kept what was packed" if args.output else "nothing saved (no --output)"),
              file=sys.stderr)
        return 130
    return 0 if report.ok else 1


def _pack_sized(args, shape):
    """``--sizes`` (and ``--solid-fraction``, ``--dense``): nd.pack_sizes, or nd.pack_dense."""
    from .drivers.dense import pack_dense
    from .drivers.greedy.protosphere import pack_sizes
    from .drivers.sizes import SizeDistribution

    if args.sizes is None:
        raise ParameterError("--dense and --solid-fraction need --sizes: radius:R, lognormal:median=M,sigma=S or "
                             "discrete:radii=R1/R2,shares=S1/S2")
    for given, name in ((args.tiles is not None, "--tiles"), (args.centers_only, "--centers-only"),
                        (args.max_radius is not None or args.min_radius, "--min-radius and --max-radius"),
                        (args.fill is not None, "--fill")):
        if given:
            raise ParameterError(f"{name} does not go with --sizes: the sizes say the radii, and -n or "
                                 "--solid-fraction how many")
    n = None if args.solid_fraction is not None else args.count
    progress = not args.quiet and sys.stderr.isatty()
    if args.dense:
        return pack_dense(shape, args.sizes, n=n, solid_fraction=args.solid_fraction, seed=args.seed,
                          backend=args.backend, time_budget=args.time_budget, progress=progress)
    sizes = args.sizes
    if not isinstance(sizes, SizeDistribution):  # equal spheres: a one-class distribution
        sizes = SizeDistribution.discrete([sizes], [1.0])
    return pack_sizes(shape, sizes, n=n, solid_fraction=args.solid_fraction, time_budget=args.time_budget,
                      grid=args.grid, iterations=args.iterations, seed=args.seed, backend=args.backend,
                      device=args.device, progress=progress, on_invalid=args.on_invalid)


#: The suffixes of the mesh files a folder given to ``ndpack pack`` stands for (those trimesh reads).
FOLDER_MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf", ".3mf")


def _tiles(text: str):
    """``--tiles``: auto (None), N, or N,N,... (per axis)."""
    if text == "auto":
        return "auto"
    try:
        counts = [int(part) for part in text.split(",")]
    except ValueError:
        counts = []
    if not counts or min(counts) < 1:
        raise argparse.ArgumentTypeError(f"give auto, a positive integer, or one per axis (4,2,2), not {text!r}")
    return counts[0] if len(counts) == 1 else counts


def _pack_tiled(args):
    """``nd.pack_tiled`` with ``--tiles`` and ``--workers``, after refusing the options it does not take."""
    from .scale.tiled import pack_tiled

    refused = [name for name, given in (("--max-radius", args.max_radius is not None), ("--fill", args.fill),
                                        ("--time", args.time_budget), ("--batch", args.batch != 1),
                                        ("--centers-only", args.centers_only)) if given]
    if refused:
        raise ParameterError(f"--tiles packs to a count (-n) or --min-radius; it does not take {', '.join(refused)}: "
                             "leave them out, or leave out --tiles")

    def tiled(shape, **options):
        return pack_tiled(shape, tiles=None if args.tiles == "auto" else args.tiles, workers=args.workers, **options)

    return tiled


def _with_dim(spec: str, dim: int | None) -> str:
    """``--dim``, added to a built-in spec as ``:dim=`` (``box`` -> ``box:dim=4``, ``annulus:inner=0.3`` ->
    ``annulus:inner=0.3,dim=4``); the spec as it is without one."""
    if dim is None:
        return spec
    _, colon, options = spec.partition(":")
    given = [value for key, _, value in (option.partition("=") for option in options.split(",")) if key == "dim"]
    if colon and given:  # box:dim=3 --dim 4 would pack a 4-D box labelled box:dim=3
        if given != [str(dim)]:
            raise ParameterError(f"{spec} says dim={','.join(given)} and --dim says {dim}: give the dimension once")
        return spec
    return spec + ("," if colon else ":") + f"dim={dim}"


def _expand_shapes(given: list[str]) -> tuple[list[str], bool]:
    """The shapes ``ndpack pack`` was given, a folder expanded to its mesh files and a pattern with
    ``*`` to the files it matches (where the shell did not: quoted, or on Windows); and whether a
    folder or a pattern was among them (so that a folder of one part still writes to a folder)."""
    import glob

    shapes, expanded = [], False
    for text in given or ["demo"]:
        path = Path(text).expanduser()
        if path.is_dir():
            found = sorted(str(p) for p in path.iterdir() if p.is_file() and p.suffix.lower() in FOLDER_MESH_SUFFIXES)
            if not found:
                raise ParameterError(f"no mesh files ({' '.join(FOLDER_MESH_SUFFIXES)}) in the folder {text}")
            shapes += found
            expanded = True
        elif "*" in text and not path.exists():
            found = sorted(glob.glob(str(path)))
            if not found:
                raise ParameterError(f"no file matches {text}")
            shapes += found
            expanded = True
        else:
            shapes.append(text)
    return shapes, expanded


def _is_folder(output: str) -> bool:
    return output.endswith(("/", os.sep)) or Path(output).expanduser().is_dir()


def _pack_many(args, shapes: list[str]) -> int:
    """``ndpack pack`` of several shapes: each part through :func:`~ndpack.scale.many.pack_many`, to a folder."""
    from .scale.many import pack_many
    from .io.shape_sources import is_mesh_file

    if args.output and not _is_folder(args.output):
        raise ParameterError(f"{len(shapes)} shapes are written to a folder, one file each: give -o a folder "
                             f"ending in / (e.g. -o out/), not {args.output}")
    if args.option:
        raise ParameterError("--option applies to one output file: pack the part alone for a format option")
    if args.periodic is not None:
        raise ParameterError("--periodic applies to one shape: pack the parts one by one to make them periodic")
    if args.tiles is not None:
        raise ParameterError("--tiles packs one shape in tiles; several shapes are packed each on its own: leave out "
                             "--tiles, or give one shape")
    if not args.output and args.format:
        raise ParameterError("--format describes the output files: give the folder with -o FOLDER/")
    if args.dim is not None:  # to each built-in spec, as for one shape; a file keeps its own dimension
        shapes = [text if is_mesh_file(text) or text.lower().endswith(".py")
                  else _with_dim(text, args.dim) for text in shapes]
    started = time.perf_counter()
    result = pack_many(
        shapes, n=args.count, out=args.output, format=args.format or "npz", workers=args.workers,
        progress=not args.quiet and sys.stderr.isatty(), holes=args.holes, sign=args.sign,
        min_radius=args.min_radius, max_radius=args.max_radius, fill=args.fill, time_budget=args.time_budget,
        grid=args.grid, iterations=args.iterations, batch=args.batch, mode=args.mode, seed=args.seed,
        backend=args.backend, device=args.device, on_invalid=args.on_invalid, centers_only=args.centers_only,
    )
    print(result.summary())
    if not args.output:
        print("saved:    nothing (give -o FOLDER/ to keep the spheres)")
    print(f"time:     {time.perf_counter() - started:.2f} s in all, {len(shapes)} parts")
    if result.interrupted:
        print("ndpack: interrupted; " + ("kept the parts finished" if args.output else "nothing saved (no --output)"),
              file=sys.stderr)
        return 130
    return 0 if result.ok else 1


def _pack_keeping_invalid(pack, output: str | None, shape, **options):
    """``pack(shape, **options)``; a packing that fails the final check is kept as made beside
    ``output`` (``.invalid.npz``), and the error says where, so that a long run is not lost."""
    try:
        return pack(shape, **options)
    except InvalidPackingError as error:
        if error.packing is None or not output:
            raise
        reason = _one_line(error).replace(f" {KEPT_IN_ERROR}", "")
        kept = _save_or_keep(error.packing, f"{output}.invalid.npz", None, {})
        raise InvalidPackingError(f"{reason} The packing as made was kept in {kept}") from error


def _check_output(path: str, format: str | None, dim: int, options: dict) -> None:
    """Refuse a bad output (format, suffix, options, dimension, folder) before packing, not after."""
    from .io import check

    check(path, format, dim, **options)
    _check_writable(path)


def _check_writable(path: str) -> None:
    """Refuse, before any work, an output whose folder is missing or cannot be written: a file
    is made there and removed (permission bits do not tell for root or read-only mounts)."""
    folder = Path(path).expanduser().resolve().parent
    if not folder.is_dir():
        raise ParameterError(f"cannot write {path}: no folder {folder}")
    try:
        tempfile.TemporaryFile(dir=folder).close()
    except OSError as error:
        raise ParameterError(f"cannot write {path}: {error.strerror or error} in {folder}") from None


def _save_or_keep(packing, path: str, format: str | None, options: dict) -> Path:
    """Save to ``path``; if that fails after all (a full disk, a bad option value), keep the
    packing as ``.npz`` beside it, else in the current folder, else in the temporary folder,
    and still report the error, so a long run is never lost."""
    from .io import save

    try:
        return save(packing, path, format, **options)
    except (NdpackError, OSError) as error:
        reason = (_one_line(error) if isinstance(error, NdpackError)
                  else f"cannot write {path}: {error.strerror or _one_line(error)}")
        name = Path(path).name + ".npz"
        for place in (str(path) + ".npz", Path.cwd() / name, Path(tempfile.gettempdir()) / name):
            try:
                kept = save(packing, place)
            except (NdpackError, OSError):
                continue
            raise NdpackError(f"{reason}; the packing was kept in {kept}") from error
        raise NdpackError(f"{reason}; and no folder could keep the packing (beside it, here, or the "
                          f"temporary folder)") from error


# ---------------------------------------------------------------------------------------- cover
def _cover(args) -> int:
    if Path(args.shape).suffix.lower() == ".urdf" or args.shape.lower().endswith(".urdf.xacro"):
        return _cover_robot(args)
    if args.package:
        raise ParameterError("--package applies to a URDF's meshes, and the shape is not a .urdf file: leave it out")
    from .drivers.collision.covering import cover
    from .drivers.collision.estimate import TooManySpheres
    from .io.shape_sources import describe, load_shape

    source = _with_dim(args.shape, args.dim)
    shape = load_shape(source, args.holes, args.sign)
    options = dict(args.option)
    if args.output:
        _check_output(args.output, args.format, shape.dim, options)
    elif options or args.format:
        raise ParameterError("--format and --option describe the output file: give it with -o PATH")
    protrusion = args.protrusion_abs
    if args.protrusion is not None:
        protrusion = args.protrusion * float(math.dist(*shape.bounds))
    started = time.perf_counter()
    try:
        covering = cover(shape, n=args.count, protrusion=protrusion, samples=args.samples,
                         check_samples=args.check_samples, seed=args.seed, backend=args.backend, device=args.device,
                         progress=not args.quiet and sys.stderr.isatty(), max_spheres=args.max_spheres or None)
    except TooManySpheres as error:
        raise _too_many(error, args, "a count (-n)") from None
    elapsed = time.perf_counter() - started
    print(f"shape:    {source} -> {shape!r}")
    asked = (f"at most {args.count}" if args.count is not None
             else f"protrusion at most {protrusion:.4g}" + (f" ({args.protrusion:.2%} of the diagonal)"
                                                            if args.protrusion is not None else ""))
    print(f"spheres:  {len(covering)} ({asked})")
    if covering.interrupted:
        print(f"stopped:  by Ctrl-C while {covering.params['interrupted']}: the spheres made so far, checked on "
              "fewer samples")
    print(f"covering: {covering.report.summary()}")
    for note in covering.notes:
        print(f"note:     {note}")
    print(f"time:     {elapsed:.2f} s")
    if args.output:
        spheres = covering.as_packing()
        spheres.params["source"] = describe(source)  # so that `ndpack verify` finds the shape
        if args.sign is not None:
            spheres.params["sign"] = args.sign
        print(f"saved:    {_save_or_keep(spheres, args.output, args.format, options)}")
    if covering.interrupted:
        print("ndpack: interrupted; " + ("kept the spheres made so far (they may leave gaps: see covering:)"
                                         if args.output else "nothing saved (no --output)"), file=sys.stderr)
        return 130
    return 0 if covering.report.covered else 1


def _too_many(error, args, count: str) -> ParameterError:
    """A covering refused as too many spheres, told in the command line's options."""
    share = args.protrusion is not None
    asked = f"--protrusion {args.protrusion:g}" if share else f"--protrusion-abs {args.protrusion_abs:g}"
    larger = (f"--protrusion {error.suggested / error.diagonal:.2g}" if share
              else f"--protrusion-abs {error.suggested:.3g}")
    return ParameterError(error.text(asked, larger, count, "--samples", "--max-spheres 0 lifts the limit"))


def _cover_robot(args) -> int:
    from .drivers.collision.estimate import TooManySpheres
    from .drivers.collision.robots import cover_urdf

    if args.format or args.option:
        raise ParameterError("--format and --option apply to one shape's file; a URDF's spheres go to a folder "
                             "(-o DIR): a URDF, a cuRobo .yml and report.json")
    if args.dim is not None:
        raise ParameterError("--dim applies to a built-in shape, not to a URDF: leave it out")
    if args.sign is not None:
        raise ParameterError("--sign applies to one mesh file; a URDF's meshes take the automatic sign: leave it out")
    if not args.output:
        raise ParameterError("give the output folder with -o DIR: a URDF's spheres are written as "
                             "<robot>_spheres.urdf, <robot>_spheres.yml and report.json")
    packages = {name: str(folder) for name, folder in args.package}
    started = time.perf_counter()
    try:
        robot = cover_urdf(args.shape, args.output, n=args.count, protrusion=args.protrusion_abs,
                           protrusion_share=args.protrusion, packages=packages or None, holes=args.holes,
                           seed=args.seed, progress=not args.quiet and sys.stderr.isatty(), samples=args.samples,
                           check_samples=args.check_samples, backend=args.backend, device=args.device,
                           max_spheres=args.max_spheres or None)
    except TooManySpheres as error:  # a share is of each link's diagonal
        raise _too_many(error, args, "a count per link (-n)") from None
    elapsed = time.perf_counter() - started
    print(robot.summary())
    print(f"time:     {elapsed:.2f} s")
    print(f"saved:    {robot.urdf}, {robot.yaml}, {robot.report}")
    if robot.interrupted:
        print(f"ndpack: interrupted; kept the {len(robot.links)} links covered before it", file=sys.stderr)
        return 130
    return 0 if robot.covered else 1


# ------------------------------------------------------------------------- saved packings
def _load(path: str):
    from .io import load

    return load(path)


def _recorded_shape(packing, override: str | None, required: bool, trust: bool = False, holes: str | None = None,
                    sign: str | None = None, period: bool = True):
    """The shape given on the command line, else the one the packing records (``params["source"]``).

    A recorded source that would run code (a script, a module, a package's plug-in) is used
    only with ``trust``: otherwise a crafted file could run anything on ``ndpack verify``.
    Where the shape is not ``required`` such a source is skipped with a note on stderr.
    A recorded mesh file is loaded with the packing's recorded ``holes`` (what inside meant when
    it was packed) unless ``holes`` is given, and so with ``sign``. With ``period`` the shape is
    made periodic along the axes whose period the packing records."""
    from .io.limits import printable
    from .io.shape_sources import code_in, is_mesh_file, load_shape

    if override:  # each dimension is compared before the shape is built: a file may name box:dim=1000000000
        shape = load_shape(override, holes, sign, dim=packing.dim)
        return _with_recorded_period(shape, packing) if period else shape
    source = packing.params.get("source")
    if source is None:
        if required:
            raise NdpackError("this packing does not record its shape (made outside `ndpack pack`): pass --shape")
        return None
    code = code_in(str(source))
    if code and not trust:
        advice = (f"ndpack does not run code a file names: if you trust it, pass --shape {printable(source)} "
                  f"(or --trust-source)")
        if required:
            raise NdpackError(f"this packing records its shape as {code}; {advice}")
        print(f"ndpack: drawn without the outline: the packing records its shape as {code}; {advice}",
              file=sys.stderr)
        return None
    if is_mesh_file(str(source)):
        if holes is None:
            holes = _recorded_choice(packing, "holes", HOLE_CHOICES, "pass --holes cap or --holes refuse")
        if sign is None:
            sign = _recorded_choice(packing, "sign", SIGN_CHOICES, "pass --sign")
    try:
        shape = load_shape(str(source), holes, sign, dim=packing.dim)
    except NdpackError as error:  # say that the file named it, and how to name another
        raise type(error)(f"the shape this packing records ({printable(source)[:80]}) is refused: "
                          f"{_one_line(error)}; pass --shape") from error
    return _with_recorded_period(shape, packing) if period else shape


def _with_recorded_period(shape, packing):
    """``shape`` made periodic along the axes whose period the packing records
    (``params["period"]``, one period or None per axis), checked: a file may hold anything."""
    periods = packing.params.get("period")
    if periods is None:
        return shape
    from .shapes.periodic import Periodic

    if not isinstance(periods, (list, tuple)) or len(periods) != shape.dim:
        raise NdpackError(f"the packing's recorded periods ({periods!r}) are not one per axis of the {shape.dim}-D "
                          "shape: pass --shape with the right shape")
    if not all(period is None or (isinstance(period, (int, float)) and not isinstance(period, bool) and period > 0)
               for period in periods):
        raise NdpackError(f"the packing's recorded periods ({periods!r}) are not each a positive number or None")
    if all(period is None for period in periods):
        return shape
    # The shape's bounds are the cell: a cell of other periods than the packing's would check
    # the spheres against images that are not theirs.
    lower, upper = shape.bounds
    for axis, period in enumerate(periods):
        extent = float(upper[axis] - lower[axis])
        if period is not None and math.isfinite(extent) and not math.isclose(extent, period, rel_tol=1e-9):
            raise NdpackError(f"the packing records a period of {period:.6g} along axis {axis}, but the shape "
                              f"{shape!r} spans {extent:.6g} there: pass --shape whose bounds are the packing's cell "
                              f"{packing.params.get('bounds', '')}".rstrip())
    return Periodic(shape, [period is not None for period in periods])


def _recorded_choice(packing, key: str, choices: tuple, advice: str) -> str | None:
    """The packing's ``params[key]`` (``"holes"``, ``"sign"``), checked against ``choices``: a file
    may hold anything."""
    value = packing.params.get(key)
    if value is not None and value not in choices:
        raise NdpackError(f"this packing records {key}={value!r}, which is none of {', '.join(choices)}: {advice}")
    return value


def _verify(args) -> int:
    """What is checked comes from --as and --periodic where given; else from the file, and then the
    verdict names what the file loosened (a file may hold anything)."""
    import dataclasses

    from .consistency import volume_problem
    from .verify import verify

    packing = _load(args.packing)
    told = args.kind is not None or args.periodic is not None
    shape = _recorded_shape(packing, args.shape, required=True, trust=args.trust_source, holes=args.holes,
                            sign=args.sign, period=not told)
    if args.periodic is not None:
        from .shapes.periodic import Periodic

        shape = Periodic(shape, None if args.periodic == "all" else args.periodic)
    if args.kind == "covering" or (args.kind is None and "covering" in packing.params):
        return _verify_covering(args, packing, shape)
    kind = None if args.kind is None else args.kind.replace("-", "_")
    report = verify(packing, shape, args.tol, independent=args.independent, kind=kind)
    if not told and packing.params.get("period") is not None:
        report = dataclasses.replace(report, from_file=report.from_file + ("period",))
    print(f"{args.packing}: {len(packing)} spheres in {packing.dim}-D against {shape!r}")
    print(f"verified: {report.summary()}")
    for note in report.notes():
        print(f"note:     {note}")
    problem = volume_problem(packing)
    if problem:
        print(f"IMPOSSIBLE: {problem}")
    return 0 if report.ok and not problem else 1


def _verify_covering(args, packing, shape) -> int:
    """A covering's spheres overlap and reach outside: check that they cover the shape, and reach
    out no farther than asked."""
    from .drivers.collision.covering import check_covering

    if args.tol is not None or args.independent:
        raise ParameterError("--tol and --independent apply to packings; this file holds a covering (its spheres "
                             "overlap and reach outside the shape), checked on fresh samples: leave them out")
    recorded = packing.params.get("covering")
    asked = recorded.get("protrusion") if isinstance(recorded, dict) else None
    report = check_covering(shape, packing.centers, packing.radii)
    print(f"{args.packing}: a covering of {len(packing)} spheres in {packing.dim}-D against {shape!r}")
    told = "" if args.kind else ", as the file records"
    print(f"checked:  as a covering{told} (spheres may overlap and reach outside): {report.summary()}")
    if not args.kind:
        print("note:     `ndpack verify --as packing` checks the spheres as a packing instead")
    too_far = asked is not None and report.max_protrusion > float(asked) * (1 + 1e-9)
    if too_far:
        print(f"REACHES OUT TOO FAR: {report.max_protrusion:.4g}, asked at most {float(asked):.4g}")
    return 0 if report.covered and not too_far else 1


def _render(args) -> int:
    from .io.limits import printable
    from .pictures import choose_up, picture

    packing = _load(args.packing)
    output = args.output or str(Path(args.packing).with_suffix(".png"))
    _check_writable(output)
    options = {}
    for name in ("size", "view", "up", "axes", "at"):
        if getattr(args, name) is not None:
            options[name] = getattr(args, name)
    if args.clip is not None:
        if len(args.clip) != 2 * packing.dim:
            raise NdpackError(
                f"--clip needs {2 * packing.dim} numbers for a {packing.dim}-D packing: a point, then a normal"
            )
        options["clip"] = (args.clip[: packing.dim], args.clip[packing.dim:])
    kind = args.kind
    draws_circles = kind == "slice" or (kind == "auto" and (packing.dim == 2 or Path(output).suffix.lower() != ".png"))
    if kind == "fill":
        _refuse(options, "a fill plot")
    elif draws_circles:
        _refuse({name: options[name] for name in ("size", "view", "clip") if name in options},
                "a picture of circles (2-D, a slice, .svg or .pdf)")
        shape = _recorded_shape(packing, args.shape, required=False, trust=args.trust_source, holes=args.holes,
                                sign=args.sign)
        if shape is not None:
            options["shape"] = shape
    print(f"wrote {picture(packing, output, kind=kind, **options)}")
    if kind != "fill" and packing.dim >= 3:  # which way is up, and why: the picture's report
        axes = (0, 1) if args.axes is None and draws_circles and packing.dim > 3 else args.axes
        up = printable(choose_up(packing, args.up or "auto", axes))  # it may name the recorded file
        print(f"up:    {up}; turn it with --up, --view AZIMUTH,ELEVATION or --axes")
    return 0


def _refuse(options: dict, picture: str) -> None:
    if options:
        given = ", ".join(f"--{name}" for name in options)
        verb, pronoun = ("does", "it") if len(options) == 1 else ("do", "them")
        raise ParameterError(f"{given} {verb} not apply to {picture}: leave {pronoun} out")


def _info(args) -> int:
    import numpy as np

    from .consistency import volume_problem
    from .io.limits import printable  # everything printed from the file: its escapes shown, not obeyed
    from .packing import repair_summary

    packing = _load(args.packing)
    radii = packing.radii
    print(f"file:       {args.packing}")
    covering = "covering" in packing.params
    if covering:
        print(f"spheres:    {len(packing)} in {packing.dim}-D, a covering (they overlap and reach outside the shape; "
              "`ndpack verify` checks that they cover it)")
    else:
        print(f"spheres:    {len(packing)} in {packing.dim}-D, {len(packing.stats.count)} rounds, "
              f"{printable(STOP_REASONS.get(packing.stop_reason, packing.stop_reason or '-'))}")
    if np.isfinite(packing.volume) and not covering:
        error = _plus_minus(packing.fill_error) if packing.volume_error else ""
        print(f"fill:       {packing.fill:.6f}{error} of volume {packing.volume:.6g}")
    problem = None if covering else volume_problem(packing)
    if problem:
        print(f"IMPOSSIBLE: {problem}")
    if len(radii):
        quartiles = np.percentile(radii, [0, 25, 50, 75, 100])
        print("radii:      min {:.4g}  q1 {:.4g}  median {:.4g}  q3 {:.4g}  max {:.4g}".format(*quartiles))
        print("            ratio max/min {:.3g}".format(radii.max() / radii.min()))
        _radius_histogram(radii)
    if not covering:
        print("repaired:   " + (printable(repair_summary(packing.repair)) if packing.repair
                                 else "no (passed the final check as made)"))
    holes = packing.params.get("holes")
    if holes is not None:
        meaning = {"cap": "an open mesh's holes closed by caps", "refuse": "open meshes refused"}
        print(f"holes:      {printable(holes)} ({meaning.get(holes, 'not an option ndpack knows')}; verify and render "
              "reload the mesh so)")
    if len(packing.stats.time):
        print(f"time:       {packing.stats.time[-1]:.2f} s")
    if packing.medial_axis is not None and len(packing.medial_axis):
        print(f"medial:     {len(packing.medial_axis)} medial-axis points")
    for key, value in sorted(packing.params.items()):
        print(f"  {printable(key)}: {printable(value)}")
    return 0


def _radius_histogram(radii, bins: int = 8, width: int = 40) -> None:
    """Counts per radius band, log-spaced: a packing's radii span orders of magnitude."""
    import numpy as np

    low, high = radii.min(), radii.max()
    edges = np.geomspace(low, high, bins + 1) if high > low else np.array([low, high + 1e-300])
    counts, _ = np.histogram(radii, edges)
    for left, right, count in zip(edges[:-1], edges[1:], counts):
        bar = "#" * int(round(width * count / max(counts.max(), 1)))
        print(f"    {left:10.4g} - {right:<10.4g} {count:9d} {bar}")


def _backends(args) -> int:
    from .backends import available
    from .kernels.compile import cache_folder, cached_modules, kept_for_next_time

    status = available()
    for name, state in status.items():
        print(f"{name:11s} {state}")
    folder = cache_folder("numba").parent
    size = sum(path.stat().st_size for path in folder.rglob("*") if path.is_file())
    modules = cached_modules()
    if kept_for_next_time():
        print(f"\ncompiled kernels are kept in {folder} ({size / 1e6:.1f} MB); deleting it is safe")
    else:
        print(f"\ncompiled kernels are not kept: the cache folder was refused (the warning above says why); this "
              f"process compiles into {folder}, removed when it ends")
    if not modules:
        print("none yet: the first packing on each backend compiles its kernels once (seconds to a minute)")
    for entry in modules:
        state = {True: "compiled", False: "not compiled yet", None: "Warp's cache not readable"}[entry["compiled"]]
        print(f"  {entry['kind']:6s} {entry['what']} ({state})")
    return 0 if any(s.startswith("ok") for s in status.values()) else 1


SAMPLES_EXAMPLES = """examples:
  ndpack samples                 # cow.obj, fandisk.obj, armadillo.obj and arm.urdf, here
  ndpack samples meshes --suffix .stl
"""


def _samples(args) -> int:
    from . import samples

    if not args.suffix.startswith("."):
        raise ParameterError(f"--suffix is a file suffix such as .obj or .stl, got {args.suffix!r}")
    notes = [samples.SAMPLES[name] for name in samples.names()] + [samples.ROBOT_NOTE]
    for path, note in zip(samples.write(args.folder, suffix=args.suffix), notes):
        print(f"{str(path):16s} {note}")
    return 0


COMMANDS = {"pack": _pack, "cover": _cover, "verify": _verify, "render": _render, "info": _info, "backends": _backends,
            "samples": _samples}


#: Options whose value is a list of numbers, which may start with a minus sign.
NUMBER_LIST_OPTIONS = ("--view", "--at", "--clip")
NUMBER_LIST = re.compile(r"^-?[\d.]+(e-?\d+)?(,-?[\d.]+(e-?\d+)?)*$")


def _join_negative_lists(argv: list[str]) -> list[str]:
    """``--view -35,20`` -> ``--view=-35,20`` and ``--up -y`` -> ``--up=-y``: argparse would take
    ``-35,20`` or ``-y`` for an option."""
    joined = []
    for token in argv:
        negative_axis = joined and joined[-1] == "--up" and re.fullmatch(r"-[xyz]", token)
        if negative_axis or (joined and joined[-1] in NUMBER_LIST_OPTIONS and token.startswith("-")
                             and NUMBER_LIST.match(token)):
            joined[-1] = f"{joined[-1]}={token}"
        else:
            joined.append(token)
    return joined


def main(argv=None) -> int:
    argv = _join_negative_lists(sys.argv[1:] if argv is None else list(argv))
    args = _parser().parse_args(argv)
    return _run(args)


def console() -> int:
    """The ``ndpack`` program: :func:`main`, with warnings printed as one line each (called in
    Python, :func:`main` leaves warnings to the caller's filters)."""
    with warnings.catch_warnings():
        warnings.showwarning = _warn_in_one_line
        return main()


def _warn_in_one_line(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as one line without a source path, its advice in the CLI's options where the CLI
    has them (``holes='cap'`` -> ``--holes cap``)."""
    text = re.sub(r"\bholes='(\w+)'", r"--holes \1", _one_line(message))
    print(f"ndpack: warning: {text}", file=sys.stderr)


def _run(args) -> int:
    try:
        return COMMANDS[args.command](args)
    except NdpackError as error:
        print(f"ndpack: error: {_one_line(error)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("ndpack: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `ndpack info x.npz | head`: the reader left; say nothing more
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as error:  # a file that cannot be read or written, in any command
        where = f": {error.filename}" if error.filename else ""
        print(f"ndpack: error: {error.strerror or _one_line(error)}{where}", file=sys.stderr)
        return 2


def _one_line(error) -> str:
    """An error's message on one line, with what a file put in it shown, never obeyed by the terminal."""
    from .io.limits import printable

    return printable(" ".join(str(error).split()))


if __name__ == "__main__":
    sys.exit(console())
