"""Compile a kernel program for Numba (CPU or CUDA) or Warp, cached by its structure.

Numba: the program's functions and the backend's own kernels (text of the same dialect) share
one namespace, and each function is replaced by its jitted dispatcher, so calls between them
resolve to compiled code. That namespace is a module written to the cache folder and imported,
so Numba can keep the machine code on disk (``cache=True``) and a new process loads it in a
fraction of a second instead of compiling for 10-40 s; Numba's cache needs a source file.
Warp reads the source of the functions it compiles, so its modules are files there as well.
Files are named by a hash of their text, so a changed program never meets a stale binary.

The text holds no number of any shape: built-in shapes are data for a tape interpreter
(:mod:`ndpack.kernels.tape`), one per dimension, and sizes such as the finite-difference step
are kernel arguments. One module is therefore compiled once per (structure, target, dimension,
float type), on first use on a machine, and says so before it does (:func:`announce`).
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ..log import notice
from .language import STACK_DEPTH

_numba_cache: dict[str, dict] = {}  # module text -> namespace
_warp_cache: dict[str, object] = {}  # module text -> module
#: Compilations seen in this process: {"numba": n, "numba-cuda": n, "warp": n}, where a
#: compilation is a Numba function compiled (not loaded from disk) or a Warp module built.
COMPILES: dict[str, int] = {}
#: Generated modules made in this process, by the same kinds: each new program text is one.
MODULES: dict[str, int] = {}
#: First-use compile time, in seconds, when this machine has not measured it yet (2 cores).
TYPICAL_SECONDS = {"numba": 15, "numba-cuda": 40, "warp": 30}
#: Generated modules start with this line, then what they hold (``ndpack backends`` lists them).
TITLE = "# ndpack kernels: "


def cache_folder(kind: str = "warp") -> Path:
    """Where generated modules of ``kind`` ("warp" or "numba") are written.

    ``$NDPACK_CACHE`` or ``~/.cache/ndpack``; where that cannot be written (a read-only home),
    a folder in the system's temporary folder, so compiling still works and the code is kept
    as long as that folder is. Python is imported from this folder and Numba unpickles its
    cache there, so a folder is made private (0700) and one that another user owns or may
    write is refused (:func:`_private`): on a shared machine anyone can create ``/tmp/ndpack-cache``.
    """
    root = os.environ.get("NDPACK_CACHE") or os.path.join(os.path.expanduser("~"), ".cache", "ndpack")
    refusals = []
    for base in (Path(root), Path(tempfile.gettempdir()) / "ndpack-cache"):
        folder = base / kind
        try:
            base.mkdir(mode=0o700, parents=True, exist_ok=True)
            folder.mkdir(mode=0o700, exist_ok=True)
        except OSError:
            continue
        problem = _private(base) or _private(folder)
        if problem:
            refusals.append(problem)
        elif os.access(folder, os.W_OK):
            return folder
    why = "; ".join(refusals) or f"{root} cannot be written"
    raise OSError(f"no safe writable folder for compiled kernels ({why}): set NDPACK_CACHE to a folder of your own")


def _private(folder: Path) -> str | None:
    """Why ``folder`` is not safe to import code from, or None where it is. A folder of
    another user is refused; one of ours that others may write (made under a umask of 002)
    loses that permission, as the refusal would otherwise ask the user to do."""
    status = folder.stat()
    if hasattr(os, "getuid") and status.st_uid != os.getuid():
        return f"{folder} belongs to another user (uid {status.st_uid})"
    if os.name == "posix" and status.st_mode & 0o022:
        try:
            folder.chmod(status.st_mode & 0o755)
        except OSError:
            return f"{folder} may be written by other users (mode {status.st_mode & 0o777:o}): chmod go-w it"
    return None


def _import_generated(text: str, kind: str):
    """``text`` written to the cache folder under a name from its hash, and imported as a module."""
    digest = hashlib.sha1(text.encode()).hexdigest()[:20]
    path = cache_folder(kind) / f"ndpack_{digest}.py"
    # Rewrite only a missing or different file: Numba's disk cache is tied to the file's time.
    if not path.exists() or path.read_text() != text:
        # Write then rename, so a concurrent process never imports half a file.
        with tempfile.NamedTemporaryFile("w", dir=path.parent, suffix=".tmp", delete=False) as handle:
            handle.write(text)
        os.replace(handle.name, path)
    name = f"ndpack_generated_{kind}_{digest}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


# ---------------------------------------------------------------------------------- notices
def announce(kind: str, what: str) -> None:
    """Say that ``kind`` ("numba", "numba-cuda" or "warp") is compiling ``what`` (the callers say
    it once per process and kind of kernels): about how long the longest such compile took on
    this machine before (or typically), and where the result is kept."""
    seconds = _measured().get(kind, TYPICAL_SECONDS[kind])
    notice(f"compiling {kind} kernels for {what} (first use on this machine, about {seconds:.0f} s; "
           f"kept in {cache_folder('numba').parent} for next time)")


def _measured() -> dict:
    try:
        return json.loads((cache_folder("numba").parent / "compile-times.json").read_text())
    except (OSError, ValueError):
        return {}


def _record(kind: str, seconds: float) -> None:
    """Keep the longest first-use compile seen of ``kind``, for the next notice's estimate."""
    times = _measured()
    if seconds > times.get(kind, 0.0):
        times[kind] = round(seconds, 1)
        try:
            (cache_folder("numba").parent / "compile-times.json").write_text(json.dumps(times))
        except OSError:
            pass


class _NumbaListener:
    """Numba's ``numba:compile`` events for ndpack's generated modules: the first one of a kind
    of kernels (a module's title) announces it; every one is counted; the outermost durations of
    a module add up to the next notice's estimate."""

    def __init__(self, kind: str):
        self.kind = kind
        self.announced: set[str] = set()
        self.depth = 0
        self.started = 0.0
        self.total: dict[str, float] = {}

    @staticmethod
    def module_of(event) -> str | None:
        function = getattr(event.data.get("dispatcher"), "py_func", None)
        module = getattr(function, "__module__", "") or ""
        return module if module.startswith("ndpack_generated_") else None

    def on_start(self, event):
        module = self.module_of(event)
        if module is None:
            return
        COMPILES[self.kind] = COMPILES.get(self.kind, 0) + 1
        title = _titles.get(module, "shapes")
        if title not in self.announced:  # one line per kind of kernels, however many modules
            self.announced.add(title)
            announce(self.kind, title)
        if self.depth == 0:
            self.started = time.perf_counter()
        self.depth += 1

    def on_end(self, event):
        module = self.module_of(event)
        if module is None:
            return
        self.depth -= 1
        if self.depth == 0:
            self.total[module] = self.total.get(module, 0.0) + time.perf_counter() - self.started
            _record(self.kind, self.total[module])


_listeners: dict[str, _NumbaListener] = {}
_titles: dict[str, str] = {}  # module name -> what it holds


def _listen() -> None:
    """Install the compile listener of Numba's CPU target (once)."""
    if "numba" in _listeners:
        return
    import numba.core.event as events

    listener = _listeners["numba"] = _NumbaListener("numba")

    class Listener(events.Listener):
        def on_start(self, event):
            listener.on_start(event)

        def on_end(self, event):
            listener.on_end(event)

    events.register("numba:compile", Listener())


class CudaKernel:
    """A numba-cuda kernel that, at its first launch in this process, announces (and counts) a
    compile where Numba's disk cache holds nothing of it yet. (numba-cuda has no compile event
    that a listener can use.)"""

    def __init__(self, kernel):
        self.kernel = kernel
        self._checked = False

    def __getitem__(self, config):
        if not self._checked:
            self._checked = True
            module = getattr(getattr(self.kernel, "py_func", None), "__module__", "")
            if not self._cached():
                COMPILES["numba-cuda"] = COMPILES.get("numba-cuda", 0) + 1
                title = _titles.get(module, "shapes")
                if title not in _announced_cuda:
                    _announced_cuda.add(title)
                    announce("numba-cuda", title)
        return self.kernel[config]

    def _cached(self) -> bool:
        cache = getattr(self.kernel, "_cache", None)
        index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
        return index is None or os.path.exists(index)  # None: the simulator, which compiles nothing

    def __getattr__(self, name):
        return getattr(self.kernel, name)


_announced_cuda: set[str] = set()


# ---------------------------------------------------------------------------------- Numba
def numba_namespace(program, target: str, kernels: str, jit_kernels) -> dict:
    """The program's functions and the backend's ``kernels`` compiled by Numba for ``target``.

    Parameters
    ----------
    program : Program
    target : "cpu" or "cuda"
    kernels : str
        Backend functions in the numba dialect; they call ``sd(p, prm)``. Their ``point()``
        becomes a local array of length ``D``.
    jit_kernels : callable
        ``jit_kernels(namespace, names)`` compiles the backend's functions in place (the
        backend knows which are device functions and which are entry points). The namespace
        is a generated module's, so it may ask Numba for ``cache=True``.

    Returns
    -------
    dict
        The namespace; the backend's entry points are in it by name.
    """
    if target == "cuda":
        from numba import cuda

        def jit(function):
            return cuda.jit(device=True)(function)

        imports = "from numba import cuda, float64, int32\n"
        local_point = f"cuda.local.array({program.dim}, float64)"
    else:
        import numba

        def jit(function):
            inline = "always" if function.__name__ in program.inline else "never"
            return numba.njit(cache=True, fastmath=False, inline=inline)(function)

        imports = "from numba import prange\n"
        local_point = f"np.empty({program.dim})"
    if target != "cuda":
        _listen()
    title = f"{program.title}, {'CUDA' if target == 'cuda' else 'CPU'}"
    header = (
        f"{TITLE}{title}\n# Generated by ndpack; do not edit.\n"
        f"import math\n\nimport numpy as np\n{imports}\nD = {program.dim}\n"
    )
    source = program.source("cuda" if target == "cuda" else "numba")
    text = header + "\n\n" + source + "\n\n" + kernels.replace("point()", local_point)
    if text in _numba_cache:  # the text holds the target, the dimension and the structure
        return _numba_cache[text]
    kind = "numba-cuda" if target == "cuda" else "numba"
    MODULES[kind] = MODULES.get(kind, 0) + 1
    module = _import_generated(text, "numba")
    _titles[module.__name__] = program.title
    namespace = module.__dict__
    for name in program.kernels:
        namespace[name] = jit(namespace[name])
    jit_kernels(namespace, [node.name for node in ast.parse(kernels).body if isinstance(node, ast.FunctionDef)])
    _numba_cache[text] = namespace
    return namespace


# ---------------------------------------------------------------------------------- Warp
def warp_module(program, float_name: str, kernels: str, device=None):
    """The program and the backend's Warp ``kernels`` as one imported module, loaded on ``device``.

    The module defines ``F`` (the float type), ``VecD`` (a point) and ``sd``; the kernels use
    them. Files are named by a hash of their text, so a structure compiles once per machine
    (Warp caches the binaries by the same text).
    """
    header = (
        f"{TITLE}{program.title}, Warp {float_name}\n# Generated by ndpack; do not edit.\n"
        "from typing import Any\n\nimport warp as wp\n\n"
        "wp.set_module_options({'enable_backward': False})  # no gradients needed: half the compile time\n\n"
        f"F = wp.{float_name}\nD = {program.dim}\n"
        f"VecD = wp.types.vector(length={program.dim}, dtype=wp.{float_name})\n"
        f"Stack = wp.types.vector(length={STACK_DEPTH}, dtype=wp.int32)  # stack() of the kernel language\n\n\n"
    )
    text = header + program.source("warp", float_name) + "\n\n" + kernels
    if text not in _warp_cache:
        MODULES["warp"] = MODULES.get("warp", 0) + 1
        _warp_cache[text] = _import_generated(text, "warp")
    module = _warp_cache[text]
    if device is not None:
        import warp as wp

        loaded = module.__dict__.setdefault("_ndpack_loaded", set())
        if str(device) not in loaded:
            if not _warp_cached(wp, module, device):
                COMPILES["warp"] = COMPILES.get("warp", 0) + 1
                announce("warp", f"{program.title} on {device}")
                started = time.perf_counter()
                wp.load_module(module, device=device)
                _record("warp", time.perf_counter() - started)
            else:
                wp.load_module(module, device=device)
            loaded.add(str(device))
    return module


def _warp_cached(wp, module, device) -> bool:
    """Whether Warp holds a binary of ``module`` for ``device`` in its kernel cache (a guess from
    its cache folder; where Warp's layout is not what this expects, False: announce anyway)."""
    try:
        identifier = wp.get_module(module.__name__).get_module_identifier()
        folder = Path(wp.config.kernel_cache_dir) / identifier
        suffixes = (".o",) if wp.get_device(device).is_cpu else (".cubin", ".ptx")
        return any(path.suffix in suffixes for path in folder.iterdir())
    except Exception:  # noqa: BLE001 - a guess for a notice, never a failure
        return False


# ---------------------------------------------------------------------------------- evaluation
_EVALUATE = '''
def evaluate_all(points, prm, out):
    for i in prange(points.shape[0]):
        out[i] = sd(points[i], prm)


def evaluate_serial(points, prm, out):
    for i in range(points.shape[0]):
        out[i] = sd(points[i], prm)
'''
#: Below this many points one thread is faster than waking Numba's thread pool.
PARALLEL_FROM = 20_000


def numba_evaluator(program):
    """A function ``(points (n, d) float64, prm (k,) float64) -> (n,) float64`` running ``sd``.

    Compiled with Numba for the CPU, parallel over points: how the NumPy backend and
    :meth:`Oracle.distance` evaluate a scalar kernel without a Python loop.
    """
    import numba

    def jit(namespace, names):
        for name in names:
            namespace[name] = numba.njit(parallel=name == "evaluate_all", cache=True)(namespace[name])

    namespace = numba_namespace(program, "cpu", _EVALUATE, jit)
    parallel, serial = namespace["evaluate_all"], namespace["evaluate_serial"]

    def evaluate(points, prm):
        out = np.empty(len(points))
        kernel = parallel if len(points) >= PARALLEL_FROM else serial
        kernel(np.ascontiguousarray(points, dtype=np.float64), prm, out)
        return out

    return evaluate


def cached_modules() -> list[dict]:
    """What the cache folder holds: one entry per generated module, newest first.

    Each entry has ``kind`` ("numba" or "warp"), ``what`` (the title line: structure, target),
    ``compiled`` (whether Numba keeps machine code of it; for Warp, whether Warp's kernel cache
    does, on any device) and ``path``.
    """
    entries = []
    for kind in ("numba", "warp"):
        folder = cache_folder(kind)
        for path in sorted(folder.glob("ndpack_*.py"), key=lambda p: p.stat().st_mtime, reverse=True):
            with open(path) as handle:
                first = handle.readline()
            what = first[len(TITLE):].strip() if first.startswith(TITLE) else "(an older ndpack's module)"
            if kind == "numba":
                compiled = any((folder / "__pycache__").glob(f"{path.stem}.*.nbi"))
            else:
                compiled = _warp_compiled_anywhere(path.stem)
            entries.append({"kind": kind, "what": what, "compiled": compiled, "path": str(path)})
    return entries


def _warp_compiled_anywhere(stem: str) -> bool | None:
    """Whether Warp's kernel cache holds a build of the generated module ``stem`` (None: unknown)."""
    try:
        import warp as wp

        folder = Path(wp.config.kernel_cache_dir)
        digest = stem.removeprefix("ndpack_")
        return any(digest in path.name for path in folder.iterdir())
    except Exception:  # noqa: BLE001 - a listing, never a failure
        return None
