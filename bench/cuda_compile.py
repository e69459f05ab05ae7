"""numba-cuda's compile of a packing's kernels, measured without a GPU (issue 48).

    python3 bench/cuda_compile.py --out bench/results/cuda_compile_2core.json
    python3 bench/cuda_compile.py --shape square --count 40

A fresh GPU machine's first mesh packing with numba-cuda spends most of its time compiling
kernels (41.6-77 s on H100s' hosts), and GPU time is scarce. Compiling is CPU work: Numba types
and lowers each kernel with the device functions it calls, and NVVM turns the LLVM into PTX.
Both run without a GPU (``numba.cuda.compile_ptx``, given NVVM and NVRTC: ``CUDA_HOME`` and
``LD_LIBRARY_PATH``), so this script measures them here, kernel by kernel:

1. a child process packs a small shape with numba-cuda under the CUDA simulator and records each
   kernel it launches with the types of its arguments (the kernels a first packing compiles);
2. a second child, without the simulator, builds the same generated module and compiles each
   recorded kernel to PTX for ``--cc`` (9.0: the H100), timing each, with NVVM's optimisation as
   ``numba_cuda_backend.CUDA_OPT`` asks.

The time of a kernel includes the device functions compiled for it first (a device function is
typed and lowered once, for the first kernel that calls it); the order is the packing's. On a
2-core machine the times are about 1.5-2x an H100 host's; the split between kernels is what
counts. ``--ptxas PATH`` times the compile of each kernel's PTX to SASS as well, which the driver
does when it loads the kernel on a GPU. ``--functions KERNEL ...`` prints those kernels' PTX lines
by function, and every run lists the device functions compiled more than once (an int constant
argument is typed as its own literal: each is another copy of the function in each kernel).

On a GPU machine, ``--on-gpu --mesh FILE`` times what a fresh machine does instead: a first packing
(3 spheres, numba-cuda, fast mode) with ndpack's and the driver's caches empty, each kernel's first
launch timed (Numba's compile, the driver's link and load), and the signatures each kernel was
compiled for (a kernel launched with other argument types compiles again).
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import machine_info, write_json


def shape_of(name: str):
    import trimesh

    import ndpack as nd

    if name == "mesh":  # any 3-D mesh: they share one generated module
        sphere = trimesh.creation.icosphere(subdivisions=2)
        return nd.TriangleMesh(sphere.vertices, sphere.faces)
    if name == "square":
        return nd.Box([0.0, 0.0], [1.0, 1.0])
    if name == "cube":
        return nd.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    raise SystemExit(f"unknown shape {name!r}: mesh, square or cube")


def record(args) -> None:
    """Child 1 (simulator): the kernels a small packing launches, with their argument types."""
    import numba
    import numpy as np

    import ndpack as nd
    from ndpack.backends import numba_cuda_backend

    launched = {}

    def typed(value):
        if hasattr(value, "_ary"):  # the simulator's device array
            value = value._ary
        if isinstance(value, np.ndarray):
            value = np.ascontiguousarray(value)
        return numba.typeof(value)

    original = numba_cuda_backend.NumbaCudaBackend._launch

    def recording(self, kernel, count, *launch_args, stream=0):
        name = getattr(kernel, "py_func", None) or getattr(kernel, "fn", None)
        name = getattr(name, "__name__", str(kernel))
        module = getattr(getattr(kernel, "fn", None), "__module__", "")
        launched.setdefault((module, name, tuple(typed(a) for a in launch_args)), len(launched))
        return original(self, kernel, count, *launch_args, stream=stream)

    numba_cuda_backend.NumbaCudaBackend._launch = recording
    from ndpack.backends import get_backend

    backend = get_backend("numba-cuda")
    backend.launch_bound = True  # a GPU's policies, so the kernels a GPU's packing launches
    shape = shape_of(args.shape)
    nd.pack(shape, n=args.count, grid=args.grid, mode="fast", backend=backend, seed=0, progress=False)
    with open(args.record, "wb") as out:
        pickle.dump({"shape": args.shape, "kernels": sorted(launched, key=launched.get)}, out)


def compile_all(args) -> None:
    """Child 2 (no simulator): each recorded kernel compiled to PTX, timed."""
    from types import SimpleNamespace

    from numba import cuda
    from numba.cuda import dispatcher

    from ndpack.backends import numba_cuda_backend

    # A device function asks the current device for its compute capability: there is none here.
    dispatcher.get_current_device = lambda: SimpleNamespace(compute_capability=tuple(args.cc))
    from ndpack.backends.numba_cuda_backend import ENTRY_NAMES, kernels_text
    from ndpack.kernels.compile import cuda_device_function, numba_namespace
    from ndpack.kernels.compiled import compiled_program
    from ndpack.kernels.tape import interpreter

    with open(args.record, "rb") as source:
        recorded = pickle.load(source)
    shape = shape_of(recorded["shape"])
    programs = {}

    def namespace_of(module):
        key = "geometry" if module.endswith("interpreter") else "shape"
        if key not in programs:
            program = compiled_program(shape).program
            if key == "geometry":
                program = interpreter(shape.dim)

            def jit(namespace, names):
                for name in names:
                    if name not in ENTRY_NAMES:
                        namespace[name] = cuda_device_function(namespace[name])

            programs[key] = numba_namespace(program, "cuda", kernels_text(program.source("cuda")), jit)
        return programs[key]

    rows = []
    for module, name, types in recorded["kernels"]:
        namespace = namespace_of(module)
        started = time.perf_counter()
        ptx, _ = cuda.compile_ptx(namespace[name], types, opt=numba_cuda_backend.CUDA_OPT, cc=tuple(args.cc))
        seconds = time.perf_counter() - started
        row = {"kernel": name, "seconds": round(seconds, 2), "ptx_lines": ptx.count("\n")}
        if args.ptxas:
            row["ptxas_seconds"] = round(ptxas_seconds(args.ptxas, ptx, args.cc), 2)
        if name in args.functions:
            row["functions"] = ptx_functions(ptx)
            for function, lines in list(row["functions"].items())[:20]:
                print(f"    {lines:6d} PTX lines  {function}", flush=True)
        rows.append(row)
        print(f"{name:24s} {seconds:7.2f} s  {row['ptx_lines']:8d} PTX lines  ptxas {row.get('ptxas_seconds', '-')} s",
              flush=True)
    # A device function is compiled once for each set of argument types it is called with, and Numba's CUDA
    # target types an int constant argument as its own literal type: each is another copy in every kernel.
    copies = {}
    for namespace in programs.values():
        for name, value in namespace.items():
            if name not in ENTRY_NAMES and len(getattr(value, "overloads", ())) > 1:
                copies[name] = [", ".join(str(t) for t in signature) for signature in value.overloads]
    for name, signatures in copies.items():
        print(f"{name}: {len(signatures)} specialisations", flush=True)
    print(json.dumps({"rows": rows, "specialisations": copies}))


def on_gpu(args) -> None:
    """A fresh machine's first numba-cuda packing of ``args.mesh``, kernel by kernel (run in a child
    with empty caches)."""
    import ndpack as nd
    from ndpack.kernels import compile as kernel_compile

    from numba.cuda import codegen

    firsts = []
    original = kernel_compile.CudaKernel.__getitem__
    # Where a first launch's time goes: NVVM (LLVM to PTX), the link (PTX to SASS: the driver's
    # or nvJitLink's ptxas) and the rest (Numba's typing and lowering, the module's load).
    spent = {"nvvm": 0.0, "link": 0.0}
    for method, part in (("get_asm_strs", "nvvm"), ("get_cubin", "link")):
        def timing(self, *method_args, _original=getattr(codegen.CUDACodeLibrary, method), _part=part, **kw):
            started = time.perf_counter()
            try:
                return _original(self, *method_args, **kw)
            finally:
                spent[_part] += time.perf_counter() - started

        setattr(codegen.CUDACodeLibrary, method, timing)

    def timed(self, config):
        launch = original(self, config)
        name = self.kernel.py_func.__name__
        if any(row["kernel"] == name and row["config"] == str(config) for row in firsts):
            return launch

        def first(*launch_args):
            before = dict(spent)
            started = time.perf_counter()
            result = launch(*launch_args)
            seconds = time.perf_counter() - started
            nvvm, link = (spent[part] - before[part] for part in ("nvvm", "link"))
            link -= nvvm if nvvm and link > nvvm else 0.0  # get_cubin asks for the PTX it lacks
            firsts.append({"kernel": name, "config": str(config), "seconds": round(seconds, 2),
                           "nvvm_s": round(nvvm, 2), "link_s": round(link, 2)})
            print(f"{name:24s} {seconds:7.2f} s  (NVVM {nvvm:.2f} s, link {link:.2f} s; first launch, {config})",
                  flush=True)
            return result

        return first

    kernel_compile.CudaKernel.__getitem__ = timed
    shape = nd.TriangleMesh.load(args.mesh)
    started = time.perf_counter()
    nd.pack(shape, 3, backend="numba-cuda", mode="fast", progress=False)
    first_packing = time.perf_counter() - started
    from ndpack.backends import get_backend

    backend = get_backend("numba-cuda")
    signatures = {}
    for entry in backend._namespaces.values():  # (program, namespace, ...)
        namespace = entry[1]
        for name, value in namespace.items():
            if isinstance(value, kernel_compile.CudaKernel):
                signatures[name] = len(value.kernel.overloads)
    from numba.cuda.cudadrv import driver

    result = {"first_packing_s": round(first_packing, 2), "first_launches": firsts,
              "signatures": {k: v for k, v in signatures.items() if v}, "nvjitlink": bool(driver._have_nvjitlink())}
    if args.link_study:
        result["link_study"] = link_study(backend, kernel_compile)
    print(json.dumps(result))


#: The kernels of a mesh's packing that take longest to link (bench/results/cuda_compile_h100_issue48_step9_now.json).
HEAVIEST = ("move_ids", "clearance_all", "index_fill_ids")


def link_study(backend, kernel_compile) -> dict:
    """The heaviest kernels' PTX linked again (to SASS) one after another, then at once in threads
    (the driver's link and NVVM release the GIL where the bindings let them), and at other
    optimisation levels: what a parallel or lighter compile would save."""
    from concurrent.futures import ThreadPoolExecutor

    from cuda.core import Linker, LinkerOptions, ObjectCode
    from numba.cuda.cudadrv import driver, nvvm

    libraries = {}
    for entry in backend._namespaces.values():
        for name, value in entry[1].items():
            if isinstance(value, kernel_compile.CudaKernel) and name in HEAVIEST:
                for overload in value.kernel.overloads.values():
                    libraries[name] = overload._codelibrary
    cc = next(iter(libraries.values()))._ensure_cc(None)

    def link(library):
        started = time.perf_counter()
        linker = driver._Linker(max_registers=None, cc=cc, lto=False)
        library._link_all(linker, cc)
        linker.complete()
        return time.perf_counter() - started

    def link_at(library, **options):
        started = time.perf_counter()
        ptx = "\n".join(library.get_asm_strs(cc=cc)).encode()
        arch = f"sm_{cc[0]}{cc[1]}{cc[2] if len(cc) > 2 else ''}"
        Linker(ObjectCode.from_ptx(ptx), options=LinkerOptions(arch=arch, **options)).link("cubin")
        return time.perf_counter() - started

    def nvvm_once(library):
        started = time.perf_counter()
        options = dict(library._nvvm_options, arch=f"compute_{cc[0]}{cc[1]}")
        nvvm.compile_ir(library.llvm_strs, **options)
        return time.perf_counter() - started

    study = {"kernels": sorted(libraries)}
    for label, work in (("link", link), ("nvvm", nvvm_once)):
        study[f"{label}_serial_s"] = {name: round(work(lib), 2) for name, lib in libraries.items()}
        started = time.perf_counter()
        with ThreadPoolExecutor(len(libraries)) as pool:
            list(pool.map(work, libraries.values()))
        study[f"{label}_threads_s"] = round(time.perf_counter() - started, 2)
        print(f"{label}: one after another {study[f'{label}_serial_s']}, in {len(libraries)} threads "
              f"{study[f'{label}_threads_s']} s", flush=True)
    for label, options in (("O0", {"optimization_level": 0}), ("ptxas -O1", {"ptxas_options": ["-O1"]}),
                           ("split 16", {"split_compile": 0})):
        try:
            study[label] = {name: round(link_at(lib, **options), 2) for name, lib in libraries.items()}
        except Exception as error:  # a backend that lacks the option  # noqa: BLE001
            study[label] = f"{type(error).__name__}: {error}"[:200]
        print(f"link, {label}: {study[label]}", flush=True)
    return study


def python_name(mangled: str) -> str:
    """The Python name in numba's mangled name: ``_ZN<length><module><length><name>...``."""
    if not mangled.startswith("_ZN"):
        return mangled
    position, parts = 3, []
    while position < len(mangled) and mangled[position].isdigit():
        digits = re.match(r"\d+", mangled[position:]).group(0)
        position += len(digits)
        parts.append(mangled[position:position + int(digits)])
        position += int(digits)
    return parts[-1] if len(parts) > 1 else mangled


def ptx_functions(ptx: str) -> dict[str, int]:
    """PTX lines of each function body (``.entry`` or ``.func``) of a module, the largest first, by
    the Python name (a specialisation after the first gets a number)."""
    sizes: dict[str, int] = {}
    names: dict[str, str] = {}  # mangled -> shown
    current = None
    for line in ptx.split("\n"):
        header = re.match(r"^\.(?:visible |weak )?\.(?:func|entry)\s+(?:\([^)]*\)\s*)?(\S+?)\($", line.strip())
        if header:
            mangled = header.group(1)
            if mangled not in names:
                name = python_name(mangled)
                copies = sum(shown.split(" #")[0] == name for shown in names.values())
                names[mangled] = name if copies == 0 else f"{name} #{copies + 1}"
            current = names[mangled]
        elif current and line.strip() == ";":  # a declaration, not a body
            current = None
        if current:
            sizes[current] = sizes.get(current, 0) + 1
            if line.startswith("}"):
                current = None
    return dict(sorted(sizes.items(), key=lambda item: -item[1]))


def ptxas_seconds(ptxas: str, ptx: str, cc) -> float:
    """Seconds of ``ptxas`` (at its default -O3, as the driver's JIT) turning ``ptx`` into SASS."""
    with tempfile.TemporaryDirectory() as folder:
        source = Path(folder, "kernel.ptx")
        source.write_text(ptx)
        started = time.perf_counter()
        subprocess.run([ptxas, f"-arch=sm_{cc[0]}{cc[1]}", str(source), "-o", str(Path(folder, "kernel.cubin"))],
                       check=True)
        return time.perf_counter() - started


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--shape", default="mesh", help="mesh (any 3-D mesh), cube or square")
    parser.add_argument("--count", type=int, default=12, help="spheres of the recording packing")
    parser.add_argument("--grid", type=int, default=4, help="its grid (the simulator runs a thread at a time)")
    parser.add_argument("--cc", type=int, nargs=2, default=[9, 0], help="compute capability compiled for")
    parser.add_argument("--ptxas", help="ptxas to time the PTX's compile to SASS with (the driver does it at load)")
    parser.add_argument("--functions", nargs="*", default=[], metavar="KERNEL",
                        help="print these kernels' PTX lines by function")
    parser.add_argument("--on-gpu", action="store_true", help="time a fresh GPU machine's first packing instead")
    parser.add_argument("--mesh", help="the mesh of --on-gpu")
    parser.add_argument("--link-study", action="store_true",
                        help="with --on-gpu: link the heaviest kernels again, serially, in threads, at other levels")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--child", choices=["record", "compile", "on-gpu"], help=argparse.SUPPRESS)
    parser.add_argument("--record", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child == "record":
        return record(args)
    if args.child == "compile":
        return compile_all(args)
    if args.child == "on-gpu":
        return on_gpu(args)
    if args.on_gpu:
        with tempfile.TemporaryDirectory() as folder:
            env = dict(os.environ, NDPACK_CACHE=folder, CUDA_CACHE_DISABLE="1")
            study = ["--link-study"] if args.link_study else []
            done = subprocess.run([sys.executable, __file__, "--child", "on-gpu", "--mesh", args.mesh, *study], env=env,
                                  check=True, stdout=subprocess.PIPE, text=True)
        print(done.stdout, end="")
        result = json.loads(done.stdout.strip().splitlines()[-1])
        if args.out:
            write_json(args.out, {"machine": machine_info(), "command": " ".join(["python3 bench/cuda_compile.py",
                                                                                 *(argv or sys.argv[1:])]), **result})
        return None
    with tempfile.TemporaryDirectory() as folder:
        recording = os.path.join(folder, "kernels.pickle")
        common = [sys.executable, __file__, "--shape", args.shape, "--count", str(args.count), "--grid", str(args.grid),
                  "--record", recording, "--cc", *map(str, args.cc),
                  *(["--ptxas", args.ptxas] if args.ptxas else []), "--functions", *args.functions]
        env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1", NDPACK_CACHE=folder)
        subprocess.run([*common, "--child", "record"], env=env, check=True)
        env = dict(os.environ, NDPACK_CACHE=folder)
        env.pop("NUMBA_ENABLE_CUDASIM", None)
        done = subprocess.run([*common, "--child", "compile"], env=env, check=True, stdout=subprocess.PIPE, text=True)
        print(done.stdout, end="")
    rows = json.loads(done.stdout.strip().splitlines()[-1])["rows"]
    total = sum(row["seconds"] for row in rows)
    print(f"{'all':24s} {total:7.2f} s")
    if args.out:
        write_json(args.out, {"machine": machine_info(), "command": " ".join(["python3 bench/cuda_compile.py",
                                                                             *(argv or sys.argv[1:])]),
                              "shape": args.shape, "cc": args.cc, "rows": rows, "seconds": round(total, 2)})


if __name__ == "__main__":
    main()
