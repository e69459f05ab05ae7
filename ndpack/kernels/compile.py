"""Compile a kernel program for Numba (CPU or CUDA) or Warp, cached by its structure.

Numba: the program's functions and the backend's own kernels (text of the same dialect) share
one namespace, and each function is replaced by its jitted dispatcher, so calls between them
resolve to compiled code. That namespace is a module written to the cache folder and imported,
so Numba can keep the machine code on disk (``cache=True``) and a new process loads it in a
fraction of a second instead of compiling for 10-40 s; Numba's cache needs a source file.
Warp reads the source of the functions it compiles, so its modules are files there as well.
Files are named by a hash of their text, so a changed program never meets a stale binary.
As Python and Numba run what they read there, the folder is trusted only when it and its files
are this user's alone (:func:`cache_root`); otherwise a process compiles into a folder of its own.

The text holds no number of any shape: built-in shapes are data for a tape interpreter
(:mod:`ndpack.kernels.tape`), one per dimension, and sizes such as the finite-difference step
are kernel arguments. One module is therefore compiled once per (structure, target, dimension,
float type), on first use on a machine, and says so before it does (:func:`announce`).
"""

from __future__ import annotations

import ast
import atexit
import hashlib
import importlib.util
import json
import os
import shutil
import stat
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from .. import compile_ahead, log
from ..log import notice, warn
from .language import STACK_DEPTH

_numba_cache: dict[str, dict] = {}  # module text -> namespace
_warp_cache: dict[str, object] = {}  # module text -> module
#: Compilations seen in this process: {"numba": n, "numba-cuda": n, "warp": n}, where a
#: compilation is a Numba function compiled (not loaded from disk) or a Warp module built.
COMPILES: dict[str, int] = {}
#: Generated modules made in this process, by the same kinds: each new program text is one.
MODULES: dict[str, int] = {}
#: First-use compile time, in seconds, when this machine has not measured that compile yet: Numba,
#: numba-cuda, Warp on a CPU (2 cores: 4 s for the 3-D meshes' kernels) and on a GPU. Numba's
#: first compiles (a cache's ``compile-times.json``) took 6.1 s for the mesh queries, 5.9 s for the
#: 3-D shapes and 11.7 s for 3-D shapes and meshes on 2 cores (``NDPACK_CACHE=$(mktemp -d) ndpack
#: pack armadillo.obj -n 3 --backend numba``), 7.4 s for the mesh queries on an H200's host; Warp
#: on an H200 3.3 s for the 3-D meshes' kernels and 2.5 s for their cooperative moves (at
#: ``WARP_OPTIMIZATION``, the driver's compile of the PTX included;
#: bench/results/compile_times_h200_issue48_step4.json). On H100s' hosts Numba took 6.0-13.5 s for
#: the mesh queries, 8.1 s for the 2-D shapes, 8.3 s for the 3-D shapes and 16.0 s for 3-D shapes and
#: meshes, and numba-cuda 18.6 s for the kernels of a mesh's first packing (their first launches;
#: 47.2 s before meshes had their own program and the move kernel one converge:
#: bench/results/cuda_compile_h100_issue48_step9_now.json). A fresh H200 at issue 48's sixteenth step:
#: Warp 3.2 s for the meshes' kernels and 1.6 s for their cooperative moves, numba-cuda 10.2 s, Numba
#: 2.9-3.5 s for the mesh queries (bench/results/fresh_machine_h200_issue48_step16.json). So the
#: estimates are within 2x of each.
TYPICAL_SECONDS = {"numba": 10, "numba-cuda": 15, "warp": 6, "warp on a GPU": 3}
#: Warp's CUDA optimisation level for ndpack's modules. At Warp's default (3) a fresh H100's first
#: packing of a mesh compiled for 90 s (most of it the driver compiling Warp's PTX) and packed the
#: armadillo's 100,000 spheres in 2.07 s; at 2, 3 s and 2.00 s (medians of 3, the driver's cache
#: off; bench/compile_options.py, docs/benchmarks.md). With the kernels written once (issue 48's
#: eleventh step), level 3 compiles the two modules in 12 s and 9 s against 4 s and 3 s, and its
#: kernels are faster by 3% (the move) to 22% (the cells' distances), the packing by about 2%
#: (``bash bench/gpu_issue48_step11.sh levels`` and ``level-turns``; measured at 1fbb251, which built
#: level 3 in the background): not worth three times the first compile, nor a background build.
WARP_OPTIMIZATION = 2
#: Generated modules start with this line, then what they hold (``ndpack backends`` lists them).
TITLE = "# ndpack kernels: "


# ---------------------------------------------------------------------------------- the cache folder
# Python imports the generated modules, and Numba unpickles its index (.nbi) and code (.nbc) files,
# from the cache folder: a file there that another user could have written is code that user runs
# as us. So the folder and every file ndpack or Numba reads in it are checked once per process,
# before any is read; after that only we (or root) can add or change files there. A folder or file
# that fails is never repaired (its mode is not ours to change): the whole cache is refused, with
# one warning line, and this process compiles into a private folder made for it alone (mkdtemp,
# 0700, removed at exit). That is the simplest safe choice: imports and Numba's ``cache=True`` work
# unchanged, and what they find there is only what this process wrote.
_roots: dict[str, Path] = {}  # configured cache folder -> the folder used for it in this process
_scratch: list[Path] = []  # this process's private folder, once made
_verdicts: dict[str, str | None] = {}  # a folder Numba caches in -> why it is refused (None: it is not)
_deciding = threading.Lock()


def _configured_root() -> Path:
    """``$NDPACK_CACHE``, else ``$XDG_CACHE_HOME/ndpack``, else ``~/.cache/ndpack``."""
    if os.environ.get("NDPACK_CACHE"):
        return Path(os.path.abspath(os.path.expanduser(os.environ["NDPACK_CACHE"])))
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    base = xdg if os.path.isabs(xdg) else os.path.join(os.path.expanduser("~"), ".cache")  # XDG: ignore relative
    return Path(base) / "ndpack"


def cache_root() -> Path:
    """The folder of ndpack's kernel cache in this process.

    ``$NDPACK_CACHE``, else ``$XDG_CACHE_HOME/ndpack``, else ``~/.cache/ndpack``, made private
    (0700) where ndpack creates it. On its first use in a process it is checked: it, its
    ``numba/`` and ``warp/`` folders, their ``__pycache__`` and every file in them must belong
    to this user, be plain files or folders, and be writable by no other user who can reach
    them (a folder's mode is never changed). Where any fails, or the folder cannot be made or
    written, one warning line names it, the reason and the folder used instead: a private
    temporary folder of this process, so kernels compile as usual but are not kept.
    """
    root = _configured_root()
    key = str(root)
    with _deciding:  # one check, and one warning, however many threads ask first
        if key not in _roots:
            problem = _open_cache(root)
            if problem is None:
                _roots[key] = root
            else:
                _roots[key] = _scratch_folder()
                warn(f"kernel cache {root} refused: {problem}; compiling into {_roots[key]} for this process "
                      "only (set NDPACK_CACHE to a folder of yours that only you may write, to keep compiled kernels)")
    root = _roots[key]
    root.mkdir(mode=0o700, parents=True, exist_ok=True)  # again where deleted meanwhile; ours if so
    for kind in KINDS:
        (root / kind).mkdir(mode=0o700, exist_ok=True)
        (root / kind / "__pycache__").mkdir(mode=0o700, exist_ok=True)
    return root


def kept_for_next_time() -> bool:
    """Whether compiled kernels are kept for the next process (False: the cache folder was refused)."""
    return cache_root() not in _scratch


def cache_folder(kind: str = "warp") -> Path:
    """Where generated modules of ``kind`` ("warp" or "numba") are written: a folder of
    :func:`cache_root`, whose ``__pycache__`` holds Numba's compiled code (and Python's)."""
    return cache_root() / kind


#: The folders of generated modules in the cache folder, one per compiler.
KINDS = ("numba", "warp")


def _open_cache(root: Path) -> str | None:
    """Make ``root`` and its folders where missing, and say why it may not be used (None: it may)."""
    if root.exists() and not root.is_dir():
        return f"{root} is not a folder"
    try:
        root.mkdir(mode=0o700, parents=True, exist_ok=True)
        problem = _untrusted(root, root) or _open_ancestors(root)
        if problem:  # nothing is made inside a folder that is refused
            return problem
        folders = [root]
        for kind in KINDS:
            (root / kind).mkdir(mode=0o700, exist_ok=True)
            # Made here, private, before Numba or Python makes it with the umask's mode.
            (root / kind / "__pycache__").mkdir(mode=0o700, exist_ok=True)
            folders += [root / kind, root / kind / "__pycache__"]
        for folder in folders:
            problem = folder != root and _untrusted(root, folder)
            if problem:
                return problem
            if not os.access(folder, os.W_OK | os.X_OK):
                return f"{folder} cannot be written"
    except OSError as error:
        return f"{error.filename or root} cannot be made or read ({error.strerror or error})"
    _verdicts.update((str(folder), None) for folder in folders if folder.name == "__pycache__")
    return None


def _open_ancestors(root: Path) -> str | None:
    """Why a folder above ``root`` lets other users replace the cache folder (None: it does not):
    one that anyone may write without the sticky bit (as ``/tmp`` has). A group-writable one is
    accepted, as a home under a umask of 002 with a group of one's own often is."""
    if os.name != "posix":
        return None
    for parent in {*root.parents, *Path(os.path.realpath(root)).parents}:  # where a link is, and where it leads
        mode = parent.stat().st_mode
        if mode & stat.S_IWOTH and not mode & stat.S_ISVTX:
            return f"{parent} above it may be written by anyone (mode {mode & 0o7777:o}), so it could be replaced"
    return None


def _untrusted(top: Path, folder: Path) -> str | None:
    """Why a file in ``folder`` (``top`` or inside it) may hold what another user wrote, or None.

    ``top``, each folder down to ``folder`` and each entry of ``folder`` must belong to us, be a
    plain file (with no other name: a hard link is another way in) or folder, and be writable by
    no one else who can reach it: a group or others may write an entry only where every folder
    above it, from ``top``, lets them in. Anyone is assumed to reach ``top``.
    """
    if os.name != "posix":
        return None  # no POSIX owner or mode to check
    reach = 0o022  # write bits (group, others) of the classes that can reach the next entry
    parts = folder.relative_to(top).parts
    chain = [top, *(top.joinpath(*parts[:i + 1]) for i in range(len(parts)))]
    for path in chain:
        problem = _entry(path, reach, follow=path == top)
        if problem:
            return problem
        reach &= (path.stat().st_mode & 0o011) << 1  # the search bits (x) of the group and of others
    for path in folder.iterdir():
        try:
            problem = _entry(path, reach)
        except FileNotFoundError:  # a temporary file of one of our processes, gone
            continue
        if problem:
            return problem
    return None


def _entry(path: Path, reach: int, follow: bool = False) -> str | None:
    status = path.stat() if follow else path.lstat()
    if status.st_uid != os.getuid():
        return f"{path} belongs to another user (uid {status.st_uid})"
    if not (stat.S_ISDIR(status.st_mode) or stat.S_ISREG(status.st_mode)):
        return f"{path} is not a plain file or folder"
    if stat.S_ISREG(status.st_mode) and status.st_nlink > 1:
        return f"{path} has other names (hard links)"
    if status.st_mode & reach:
        return f"{path} may be written by other users (mode {status.st_mode & 0o7777:o})"
    return None


def _scratch_folder() -> Path:
    """This process's private folder for generated modules, made at its first use."""
    if not _scratch:
        folder = Path(tempfile.mkdtemp(prefix="ndpack-kernels-"))  # 0700, a new name: ours alone
        atexit.register(shutil.rmtree, folder, ignore_errors=True)
        _scratch.append(folder)
    return _scratch[0]


def _checked_disk_caches(namespace: dict) -> None:
    """Numba keeps each function's code in the ``__pycache__`` checked by :func:`cache_root`,
    unless ``NUMBA_CACHE_DIR`` (or a folder that cannot be written) sends it elsewhere: such a
    folder is checked the same way (from ``NUMBA_CACHE_DIR`` down) before Numba reads it, and
    where it fails, with one warning line, the functions cached there compile without a disk cache."""
    for value in namespace.values():
        dispatcher = getattr(value, "kernel", value)  # a CudaKernel wraps its dispatcher
        path = getattr(getattr(dispatcher, "_cache", None), "cache_path", None)
        if not path:
            continue
        if path not in _verdicts:
            from numba.core import config

            top = Path(config.CACHE_DIR) if config.CACHE_DIR else Path(path)
            try:
                top = top if Path(path).is_relative_to(top) else Path(path)
                _verdicts[path] = _untrusted(top, Path(path))
            except OSError as error:
                _verdicts[path] = f"{path} cannot be read ({error.strerror or error})"
            if _verdicts[path]:
                warn(f"Numba's disk cache {path} refused: {_verdicts[path]}; ndpack's kernels are compiled "
                      "without it in this process")
        if _verdicts[path]:
            # The dispatcher's own module holds the NullCache it starts with (numba and numba-cuda).
            owner = next(k for k in type(dispatcher).__mro__ if "enable_caching" in vars(k))
            dispatcher._cache = sys.modules[owner.__module__].NullCache()


def _import_generated(text: str, kind: str):
    """``text`` written to the cache folder under a name from its hash, and imported as a module."""
    digest = hashlib.sha1(text.encode()).hexdigest()[:20]
    path = cache_folder(kind) / f"ndpack_{digest}.py"
    # Rewrite only a missing or different file: Numba's disk cache is tied to the file's time.
    if not path.exists() or path.read_text() != text:
        _write(path, text)
    name = f"ndpack_generated_{kind}_{digest}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def import_generated_again(digest: str, kind: str = "numba"):
    """The generated module of ``digest`` (as :func:`_import_generated` names its file) that another
    process wrote to the cache folder, imported here under the same name: how a compile helper
    (:mod:`ndpack.compile_ahead`) compiles the very functions that process will load. Raises
    FileNotFoundError where this process's cache folder lacks it (one of them was refused)."""
    if not all(c in "0123456789abcdef" for c in digest):
        raise ValueError(f"not a generated module's digest: {digest!r}")
    text = (cache_folder(kind) / f"ndpack_{digest}.py").read_text()
    return _import_generated(text, kind)


def _write(path: Path, text: str) -> None:
    """Write then rename, so a concurrent process never reads half a file; the file is private
    (0600, from mkstemp) whatever the umask."""
    with tempfile.NamedTemporaryFile("w", dir=path.parent, suffix=".tmp", delete=False) as handle:
        handle.write(text)
    os.replace(handle.name, path)


# ---------------------------------------------------------------------------------- notices
def announce(kind: str, what: str, typical: float | None = None, where: str | None = None) -> None:
    """Say that ``kind`` ("numba", "numba-cuda" or "warp") is compiling ``what`` (the callers say
    it once per process and kind of kernels): about how long the last compile of these kernels
    took on this machine (:func:`_record`), else ``typical`` (default ``TYPICAL_SECONDS[kind]``),
    and where the result is kept (``where``, else ndpack's cache folder)."""
    fallback = TYPICAL_SECONDS[kind] if typical is None else typical
    seconds = _measured().get(_estimate_key(kind, what), fallback)
    if where is None and not kept_for_next_time():
        kept = "not kept: the cache folder was refused"
    else:
        kept = f"kept in {where or cache_root()} for next time"
    notice(f"compiling {kind} kernels for {what} (first use on this machine, about {max(seconds, 1):.0f} s; {kept})")


def _measured() -> dict:
    try:
        times = json.loads((cache_root() / "compile-times.json").read_text())
    except (OSError, ValueError):
        return {}
    if not isinstance(times, dict):
        return {}
    return {kind: seconds for kind, seconds in times.items() if isinstance(seconds, (int, float))}


def _estimate_key(kind: str, what: str) -> str:
    return f"{kind}: {what}"


def _record(kind: str, seconds: float, what: str | None = None) -> None:
    """Keep the longest first-use compile seen of ``kind`` and, with ``what``, the last time these
    kernels took, which the next notice for them gives: the same kernels compile alike, while a
    kind's longest may be other kernels, or older code (a compile made faster would keep being
    announced at its old length)."""
    times = _measured()
    changed = seconds > times.get(kind, 0.0)
    if changed:
        times[kind] = round(seconds, 1)
    if what is not None:
        times[_estimate_key(kind, what)], changed = round(seconds, 1), True
    if changed:
        try:
            _write(cache_root() / "compile-times.json", json.dumps(times))
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
        self.title_total: dict[str, float] = {}  # the kernels' title -> their modules' compile time

    @staticmethod
    def module_of(event) -> str | None:
        function = getattr(event.data.get("dispatcher"), "py_func", None)
        module = getattr(function, "__module__", "") or ""
        return module if module.startswith("ndpack_generated_") or module in _own else None

    def on_start(self, event):
        module = self.module_of(event)
        if module is None:
            return
        own = _own.get(module)
        if own is None:  # ndpack's own functions are not generated modules: not counted
            COMPILES[self.kind] = COMPILES.get(self.kind, 0) + 1
        title = own[0] if own else _titles.get(module, "shapes")
        if title not in self.announced:  # one line per kind of kernels, however many modules
            self.announced.add(title)
            announce(self.kind, title, *(own[1:] if own else ()))
        if self.depth == 0:
            self.started = time.perf_counter()
        self.depth += 1

    def on_end(self, event):
        module = self.module_of(event)
        if module is None:
            return
        self.depth -= 1
        if self.depth == 0:
            spent = time.perf_counter() - self.started
            own = _own.get(module)
            if own is None:
                self.total[module] = self.total.get(module, 0.0) + spent
            title = own[0] if own else _titles.get(module, "shapes")
            self.title_total[title] = self.title_total.get(title, 0.0) + spent
            _record(self.kind, self.title_total[title], title)


_listeners: dict[str, _NumbaListener] = {}
_titles: dict[str, str] = {}  # module name -> what it holds
#: ndpack's own Numba functions (``numba.njit(cache=True)`` in its modules, cached beside them):
#: module name -> (what they are, their first compile's typical seconds, where Numba keeps them).
#: Announced like the generated modules' kernels, not counted in ``COMPILES``.
_own: dict[str, tuple[str, float, str]] = {}


def own_kernels(module: str, what: str, typical: float) -> None:
    """Announce the first compile on this machine of the Numba functions of ndpack's ``module``
    as ``what``, about ``typical`` seconds until the machine has timed it (call before compiling)."""
    import numba

    where = numba.config.CACHE_DIR or str(Path(sys.modules[module].__file__).parent / "__pycache__")
    _own[module] = (what, typical, where)
    _listen()


log.own_compile_hook = own_kernels  # the geometry layer's Numba functions call it through ndpack.log


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
    compile where Numba's disk cache holds nothing of it yet, and times that launch, which
    compiles it: the kernels' times add up to the next notice's estimate for their title, as
    the CPU kernels' do. (numba-cuda has no compile event that a listener can use.) Where a
    compile helper has it (``ahead``, a job key of :mod:`ndpack.compile_ahead`), the first launch
    waits for that helper, then loads the kernel from disk; the wait counts as its compile."""

    def __init__(self, kernel):
        self.kernel = kernel
        self.ahead: str | None = None
        self._checked = False

    def __getitem__(self, config):
        launch = self.kernel[config]
        if self._checked:
            return launch
        self._checked = True
        title = _titles.get(getattr(getattr(self.kernel, "py_func", None), "__module__", ""), "shapes")
        if self.ahead is not None:
            _cuda_compile_time(title, compile_ahead.wait(self.ahead))
        if self._cached():
            return launch
        COMPILES["numba-cuda"] = COMPILES.get("numba-cuda", 0) + 1
        announce_cuda(title)

        def compiling(*args):
            started = time.perf_counter()
            result = launch(*args)  # compiles, then queues the launch
            _cuda_compile_time(title, time.perf_counter() - started)
            return result

        return compiling

    def _cached(self) -> bool:
        cache = getattr(self.kernel, "_cache", None)
        index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
        return index is None or os.path.exists(index)  # None: the simulator, which compiles nothing

    def __getattr__(self, name):
        return getattr(self.kernel, name)


def announce_cuda(title: str) -> None:
    """Say numba-cuda's first compile of the kernels of ``title`` (once a process)."""
    if title not in _announced_cuda:
        _announced_cuda.add(title)
        announce("numba-cuda", title)


def cuda_title(namespace: dict) -> str:
    """What the numba-cuda kernels of a generated ``namespace`` are for (their notices' words)."""
    return _titles.get(namespace.get("__name__", ""), "shapes")


def _cuda_compile_time(title: str, seconds: float) -> None:
    """Add ``seconds`` to this process's compile time of the numba-cuda kernels of ``title``."""
    if seconds > 0:
        _cuda_seconds[title] = _cuda_seconds.get(title, 0.0) + seconds
        _record("numba-cuda", _cuda_seconds[title], title)


_announced_cuda: set[str] = set()
_cuda_seconds: dict[str, float] = {}  # a title -> its numba-cuda kernels' compile time in this process


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
        jit = cuda_device_function
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
    jit_generated(namespace, list(program.kernels), function_names(kernels), jit, jit_kernels)
    _numba_cache[text] = namespace
    return namespace


def function_names(text: str) -> list[str]:
    """The names of the top-level functions of ``text``, in order."""
    return [node.name for node in ast.parse(text).body if isinstance(node, ast.FunctionDef)]


def jit_generated(namespace: dict, program_names, kernel_names, jit, jit_kernels) -> None:
    """A generated module's ``namespace`` jitted in place: the program's functions by ``jit``, the
    backend's ``kernel_names`` by ``jit_kernels(namespace, names)``; its disk caches checked before
    the first call, when Numba reads its index. What :func:`numba_namespace` does, and a compile
    helper again for the same module (:func:`import_generated_again`), so that both compile the
    same functions with the same options."""
    for name in program_names:
        namespace[name] = jit(namespace[name])
    jit_kernels(namespace, kernel_names)
    _checked_disk_caches(namespace)


def cuda_device_function(function):
    """numba-cuda's device function of ``function``, compiled once for each set of argument types
    with int and float constants typed as their type, not as their value.

    numba-cuda types a constant argument as its own literal, so each constant a function is called
    with is another copy of it in every kernel that calls it: the mesh's triangle query was three
    (``want`` 0, 1 and any), 4,500 of the move kernel's 39,700 PTX lines, and the index queries'
    flags two or three each (``bench/cuda_compile.py`` lists such copies). The branches on such
    an argument cost a comparison at run time.
    """
    from numba import cuda
    from numba.core import types

    dispatcher = cuda.jit(device=True)(function)
    if not hasattr(dispatcher, "get_call_template"):  # the simulator's: it compiles nothing
        return dispatcher
    resolve = dispatcher.get_call_template

    def get_call_template(args, kws):
        return resolve(tuple(types.unliteral(a) for a in args), {k: types.unliteral(v) for k, v in kws.items()})

    dispatcher.get_call_template = get_call_template
    return dispatcher


# ---------------------------------------------------------------------------------- Warp
def warp_module(program, float_name: str, kernels: str, device=None, block_dim: int | None = None,
                what: str = ""):
    """The program and the backend's Warp ``kernels`` as one imported module, loaded on ``device``.

    The module defines ``F`` (the float type), ``VecD`` (a point) and ``sd``; the kernels use
    them. Files are named by a hash of their text, so a structure compiles once per machine
    (Warp caches the binaries by the same text). ``block_dim``: the threads of a block its
    launches use (Warp compiles a module once per block size; default Warp's); ``what``: words
    added to the compile notice's name of the module.
    """
    options = f"'enable_backward': False, 'optimization_level': {WARP_OPTIMIZATION}"
    if block_dim is not None:
        options += f", 'block_dim': {block_dim}"
    header = (
        f"{TITLE}{program.title}{what}, Warp {float_name}\n# Generated by ndpack; do not edit.\n"
        "from typing import Any\n\nimport warp as wp\n\n"
        "# No gradients needed: half the compile time. Optimisation level: see ndpack's WARP_OPTIMIZATION.\n"
        f"wp.set_module_options({{{options}}})\n\n"
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
                what = f"{program.title}{what} on {device}"
                announce("warp", what, TYPICAL_SECONDS["warp on a GPU" if wp.get_device(device).is_cuda else "warp"])
                started = time.perf_counter()
                wp.load_module(module, device=device, block_dim=block_dim)
                _record("warp", time.perf_counter() - started, what)
            else:
                wp.load_module(module, device=device, block_dim=block_dim)
            loaded.add(str(device))
    return module


def _warp_cached(wp, module, device) -> bool:
    """Whether Warp holds a binary of ``module`` for ``device`` in its kernel cache (a guess from
    its cache folder; where Warp's layout is not what this expects, False: announce anyway)."""
    try:
        # A module's name is a hash of its text, options included, so any build of it is this one.
        # (Warp names the folder by the name and a hash for the launches' block size, which on a CPU
        # is 1 where the module's default is 256: asked for the default's folder, every cached CPU
        # module was announced as compiling.)
        target = wp.get_device(device)
        suffixes = (".o",) if target.is_cpu else (".cubin", ".ptx")
        arch = "" if target.is_cpu else f".sm{target.arch}"
        return any(path.suffix in suffixes and arch in path.name
                   for folder in Path(wp.config.kernel_cache_dir).glob(f"wp_{module.__name__}_*")
                   for path in folder.iterdir())
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
