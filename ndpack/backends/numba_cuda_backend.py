"""The Numba CUDA backend: the Numba backend's per-point work as CUDA kernels, one thread each.

The per-point functions are the CPU backend's (:mod:`ndpack.backends.numba_kernels`), compiled as
device functions; the prototype store's kernels and the sphere index's queries are written once for
this backend and Warp's (:mod:`ndpack.backends.store_kernels`,
:mod:`ndpack.backends.index_kernels`). The inserted spheres live on the device and only new ones
are copied up (:class:`~ndpack.backends.device_spheres.DeviceSpheres`), and during a packing so do
the prototypes (:class:`~ndpack.backends.prototypes.DevicePrototypes`, through
:class:`_CudaDevice`); the array operations copy their inputs per call. float64 throughout: an H100
runs float64 at half its float32 rate, and the packing stays as exact as the CPU's. Small move
launches and the set-up's converge walk a mesh's tree with a block of 32 threads per prototype
(:mod:`ndpack.backends.numba_cuda_lanes`).

Without a GPU, set ``NUMBA_ENABLE_CUDASIM=1`` to run the same kernels in Numba's CUDA simulator
(slow; for tests).
"""

from __future__ import annotations

import weakref
from pathlib import Path

import numpy as np

from ..errors import BackendError
from .. import compile_ahead
from ..kernels.compile import (CudaKernel, announce_cuda, cuda_device_function, cuda_title, function_names,
                               import_generated_again, jit_generated, numba_namespace)
from ..kernels.compiled import compiled_program
from ..kernels.portable import kernel_argument_types, kernel_names, render
from ..kernels.tape import interpreter
from .base import Backend, staging_rows, tightened_reach
from .device_spheres import DeviceSpheres
from .kernel_texts import STORE, portable_text
from .numba_common import FD_STEP, KERNELS
from .numba_cuda_lanes import CONVERGE_MOST, COOPERATIVE_MOST, LANES, has_walk, lanes_text, shared_bytes
from .numba_cuda_launch import Replay
from .prototypes import SPREAD_MAX, DevicePrototypes, converge_by_move

# The GPU backends' kernels (the prototype store's, the device index's build, clearances, touches, the
# spheres near boxes): written once for both (ndpack.backends.store_kernels), printed for numba-cuda.
STORE_TEXT = portable_text(STORE)
STORE_KERNELS = render(STORE_TEXT, "cuda")
# The move's launch, numba-cuda's own: one kernel serves the cooperative launch (a block per prototype)
# and the plain one, where Warp has a module for each.
MOVE_ENTRY = '''
def move_ids(ids, first, first_rows, tries, stream, points, clearance, polished, lower, upper, wall, prm, centers,
             radii, nbr, steps, h, polish, spread, polish_steps, polish_low, polish_from):
    # A block of LANES threads is one prototype's, which walk together (ndpack.backends.numba_cuda_lanes);
    # in other launches thread b * spread moves prototype b and the spread - 1 after it idle.
    lane = 0
    if cuda.blockDim.x == LANES:
        b = cuda.blockIdx.x
        lane = cuda.threadIdx.x
    else:
        t = cuda.grid(1)
        b = t // spread
        if t % spread != 0:
            return
    if b < ids.shape[0]:
        move_one_lanes(b, lane, ids, first, first_rows, tries, stream, points, clearance, polished, lower, upper,
                       wall, prm, centers, radii, nbr, steps, h, polish, polish_steps, polish_low, polish_from)
'''
ENTRY_NAMES = ("move_ids", *kernel_names(STORE_TEXT))
#: The move launch's argument types, named as the store's kernels' annotations
#: (:data:`ndpack.kernels.portable.ARGUMENT_TYPES`): its text is numba-cuda's own, unannotated.
MOVE_ENTRY_TYPES = ("ints", "points", "int", "int", "u64", "points", "floats", "ints", "points", "points",
                    "floats", "floats", "points", "floats", "int_table", "floats", "float", "int", "int", "floats",
                    "float", "int")
#: Every entry point's argument types, in order: the signature a compile helper compiles it for
#: (:func:`compile_kernels`), the one its launches give it (tests/backends/test_compile_ahead.py).
ENTRY_TYPES = {"move_ids": MOVE_ENTRY_TYPES, **kernel_argument_types(STORE_TEXT)}
#: How long each entry point takes to compile, relatively (a fresh H100 host's first launches of a
#: mesh's kernels, 0.4-5 s: bench/results/cuda_compile_h100_issue48_step9_now.json; cell_distances
#: walks the mesh as clearance_all does); the others about 0.1 s. The helpers share them by it.
COMPILE_WEIGHTS = {"move_ids": 5.0, "clearance_all": 3.9, "cell_distances": 3.0, "index_bound_ids": 1.9,
                   "index_fill_ids": 0.6, "touched_index_select": 0.4}
#: Threads of a block in the one-thread-per-item launches; never LANES, which marks a cooperative launch.
THREADS_PER_BLOCK = 128
#: NVVM's optimisation of the kernels (numba-cuda's ``opt``; Numba's default is on). Off, a fresh H100's
#: first compile of the armadillo's kernels took 58 s against 77 s, and 100,000 spheres 1.45 s against
#: 1.50 s (medians of 3, the same packing; ``bash bench/gpu_issue48_step7.sh cuda-compile``): the time
#: goes to Numba's typing and lowering of the inlined mesh walk more than to NVVM.
CUDA_OPT = False


def kernels_text(source: str, simulator: bool = False) -> str:
    """The backend's functions and entry points in the numba dialect for the program whose CUDA
    ``source`` is given, with the cooperative chain (:func:`~ndpack.backends.numba_cuda_lanes.lanes_text`;
    its lane primitives through shared memory for Numba's CUDA ``simulator``)."""
    cooperative = lanes_text(source + "\n\n" + KERNELS, simulator=simulator)
    return KERNELS + cooperative + STORE_KERNELS + MOVE_ENTRY


class NumbaCudaBackend(Backend):
    """Numba CUDA kernels on one GPU (or the CUDA simulator), float64.

    Parameters
    ----------
    device : int
        CUDA device number.
    """

    name = "numba-cuda"

    def __init__(self, device: int = 0):
        import numba
        from numba import cuda

        # Small launches (a few touched prototypes) are expected; their occupancy warning is noise.
        numba.config.CUDA_LOW_OCCUPANCY_WARNINGS = 0
        if not numba.config.ENABLE_CUDASIM and not hasattr(np, "row_stack"):
            # Else the first kernel's compile fails deep inside numba-cuda (an H100 image's NumPy 2.5).
            from importlib.metadata import version

            raise BackendError(
                f"numba-cuda {version('numba-cuda')} cannot compile kernels with NumPy {np.__version__}: it "
                "needs np.row_stack, which NumPy 2.5 removed; install 'numpy<2.5' or a numba-cuda release that "
                "supports this NumPy, or use backend='warp'"
            )
        if not cuda.is_available():
            raise BackendError(
                "numba-cuda found no usable CUDA GPU (driver or device missing); set "
                "NUMBA_ENABLE_CUDASIM=1 to run its kernels on the CPU simulator"
            )
        self.cuda = cuda
        self.device = int(device)
        self.launch_bound = not numba.config.ENABLE_CUDASIM  # the simulator runs a launch item by item
        # Threads per prototype in a move launch, at most (prototypes.lane_spread); idle ones cost a CPU.
        self.move_spread = SPREAD_MAX if self.launch_bound else 1
        # A move launch of more than one thread per prototype and at most cooperative_most prototypes,
        # and a converge of at most cooperative_converge_most points, walk a mesh's tree with a block
        # of LANES threads per item (0: never; see numba_cuda_lanes).
        self.cooperative_most = COOPERATIVE_MOST if self.launch_bound else 0
        self.cooperative_converge_most = CONVERGE_MOST if self.launch_bound else 0
        self.move_block = THREADS_PER_BLOCK  # threads of a block in a move launch that is not cooperative
        self._simulator = bool(numba.config.ENABLE_CUDASIM)
        # Launches replayed from their recorded arguments (numba_cuda_launch); the simulator's kernels are not
        # numba-cuda's compiled ones.
        self._replay = None if self._simulator else Replay()
        cuda.select_device(self.device)
        self._namespaces = {}  # id(program) -> (program, namespace, whether it walks a tree)
        self._params = weakref.WeakKeyDictionary()  # shape -> its numbers on the device
        self._spheres = DeviceSpheres(
            empty=lambda capacity, dim: (cuda.device_array((capacity, dim)), cuda.device_array(capacity)),
            write=_write_rows,
            keep=_keep_rows,
            view=lambda array, count: array[:count],
        )

    def _jit(self, namespace, names):
        _jit_entries(self.cuda, namespace, names)

    def _kernels(self, shape):
        """The compiled namespace that runs ``shape``, its numbers on the device and its
        finite-difference step."""
        flat = compiled_program(shape)
        if shape not in self._params:
            self._params[shape] = self.cuda.to_device(flat.params)
        return self._program_kernels(flat.program, ahead=True), self._params[shape], FD_STEP * shape.scale

    def _program_kernels(self, program, ahead=False):
        """The compiled namespace of ``program``; the first time, with ``ahead``, its entry points
        that Numba's disk cache lacks go to compile helpers (:meth:`_compile_ahead`)."""
        if id(program) not in self._namespaces:
            source = program.source("cuda")  # rendered once here (numba_namespace renders its own)
            text = kernels_text(source, self._simulator)
            namespace = numba_namespace(program, "cuda", text, self._jit)
            self._namespaces[id(program)] = (program, namespace, has_walk(source))
            if ahead and not self._simulator:
                self._compile_ahead(program, namespace, text)
        return self._namespaces[id(program)][1]

    def _compile_ahead(self, program, namespace, text):
        """Where this machine has not compiled ``namespace``'s entry points yet, compile them in
        helper processes side by side (:mod:`ndpack.compile_ahead`; from 3 helpers up, since one
        would compile them one after the other as this process would), each of its first launch
        then waiting for its helper and loading it from Numba's disk cache."""
        missing = [name for name in ENTRY_TYPES if not namespace[name]._cached()]
        digest = Path(namespace["__file__"]).stem.removeprefix("ndpack_")
        backend_names = function_names(text)
        jobs = [(f"numba-cuda {digest} {name}", COMPILE_WEIGHTS.get(name, 0.1), f"{__name__}:compile_kernels",
                 [digest, list(program.kernels), backend_names, {name: list(ENTRY_TYPES[name])}, self.device])
                for name in missing]
        if len(missing) > 1 and compile_ahead.start(jobs, least=3):
            announce_cuda(cuda_title(namespace))
            under_way = set(compile_ahead.under_way())
            for (key, *_), name in zip(jobs, missing):
                namespace[name].ahead = key if key in under_way else None

    def _walks(self, shape) -> bool:
        """Whether ``shape``'s kernels walk a tree (and so have a cooperative walk)."""
        program = compiled_program(shape).program
        self._program_kernels(program)
        return self._namespaces[id(program)][2]

    def _geometry(self, dim):
        """The shape-free kernels (near_spheres, touched) for dimension ``dim``: those of the
        tape interpreter's namespace, which the shapes of built-ins share."""
        return self._program_kernels(interpreter(dim))

    def _launch(self, kernel, count, *args, stream=0, threads=THREADS_PER_BLOCK, shared=0, blocks=None):
        """``count`` items of ``kernel`` in blocks of ``threads`` (or ``blocks`` of them, with ``shared``
        bytes of shared memory each)."""
        if blocks is None:
            blocks = (count + threads - 1) // threads
        if not blocks:
            return
        if self._replay is None:
            kernel[blocks, threads, stream, shared](*args)
        else:
            self._replay.launch(kernel, blocks, threads, stream, args, shared)

    def _spheres_and_table(self, centers, radii, neighbours):
        d_centers, d_radii = self._device_spheres(centers, radii)
        table = neighbours if neighbours.shape[1] else np.full((len(neighbours), 1), len(centers))
        return d_centers, d_radii, self.cuda.to_device(np.ascontiguousarray(table, dtype=np.int64))

    def _free_space(self, shape, points, centers, radii, neighbours, directions):
        namespace, params, h = self._kernels(shape)
        d_centers, d_radii, table = self._spheres_and_table(centers, radii, neighbours)
        out = self.cuda.device_array(max(len(points), 1), dtype=np.float64)
        out_direction = self.cuda.device_array((len(points) if directions else 0, shape.dim), dtype=np.float64)
        self._launch(namespace["clearance_all"], len(points), self.cuda.to_device(_f64(points)), params,
                     d_centers, d_radii, table, h, out, out_direction)
        return out.copy_to_host()[: len(points)], out_direction.copy_to_host()

    def distance(self, shape, points):
        # With no spheres the clearance is minus the distance, exactly: one kernel fewer to compile.
        none = np.zeros((len(points), 0), dtype=np.int64)
        return -self._free_space(shape, points, np.zeros((0, shape.dim)), np.zeros(0), none, directions=False)[0]

    def converge(self, shape, points, cell_lower, cell_upper, centers, radii, neighbours, steps, wall=None,
                 starts=None):
        """The base class's converge, run by the move kernel: see
        :func:`~ndpack.backends.prototypes.converge_by_move`."""
        return converge_by_move(self, _CudaDevice(self, shape), shape, _f64(points), _f64(cell_lower),
                                _f64(cell_upper), _f64(centers), _f64(radii), neighbours, _f64(steps), wall, starts)

    def near_spheres(self, box_lower, box_upper, reach, centers, radii, return_bound=False):
        if return_bound:
            table = self.near_spheres(box_lower, box_upper, reach, centers, radii)
            return table, tightened_reach(box_lower, box_upper, reach, centers, radii, table)
        count = len(box_lower)
        if len(centers) == 0 or count == 0:
            return np.zeros((count, 0), dtype=np.int64)
        namespace = self._geometry(box_lower.shape[1])
        d_centers, d_radii = self._spheres.sync(_f64(centers), _f64(radii))
        to = self.cuda.to_device
        args = (to(_f64(box_lower)), to(_f64(box_upper)), to(_f64(reach)), d_centers, d_radii)
        counts = self.cuda.device_array(count, dtype=np.int64)
        # First pass counts (into a one-column scratch table), second fills a table that fits.
        self._launch(namespace["near_all"], count, *args, counts, self.cuda.device_array((count, 1), dtype=np.int64))
        width = int(counts.copy_to_host().max())
        out = to(np.full((count, max(width, 1)), len(centers), dtype=np.int64))
        if width:
            self._launch(namespace["near_all"], count, *args, counts, out)
        return out.copy_to_host()[:, :width]

    def prototypes(self, shape, cell_lower, cell_upper, reach, points, clearance, wall=None):
        """The prototypes on the GPU (see :class:`~ndpack.backends.prototypes.DevicePrototypes`)."""
        return DevicePrototypes(_CudaDevice(self, shape), cell_lower, cell_upper, reach, points, clearance, wall,
                                spread=self.move_spread)

    def _device_spheres(self, centers, radii):
        """Device copies of the spheres; one at infinity stands in for none, so no array is empty."""
        if len(centers) == 0:
            centers, radii = np.full((1, centers.shape[1]), 1e30), np.zeros(1)
        return self._spheres.sync(_f64(centers), _f64(radii))

    def touched(self, points, clearance, new_centers, new_radii):
        namespace = self._geometry(points.shape[1])
        to = self.cuda.to_device
        out = self.cuda.device_array(len(points), dtype=np.int64)
        self._launch(namespace["touched_all"], len(points), to(_f64(points)), to(_f64(clearance)),
                     to(_f64(new_centers)), to(_f64(new_radii)), out)
        return out.copy_to_host()


_helper_namespaces: dict[str, dict] = {}  # in a compile helper: digest -> the namespace it compiles


def _jit_entries(cuda, namespace, names):
    """The backend's functions ``names`` of ``namespace`` jitted in place: the entry points as
    kernels kept on disk (with the device functions compiled into them), the others as device
    functions."""
    for name in names:
        if name in ENTRY_NAMES:
            namespace[name] = CudaKernel(cuda.jit(cache=True, opt=CUDA_OPT)(namespace[name]))
        else:
            namespace[name] = cuda_device_function(namespace[name])


def compile_kernels(digest: str, program_names: list[str], backend_names: list[str],
                    kernels: dict[str, list[str]], device: int = 0) -> None:
    """A compile helper's job (:mod:`ndpack.compile_ahead`): the entry points ``kernels`` (name ->
    argument types, as :data:`ENTRY_TYPES`) of the generated module ``digest``, compiled for GPU
    ``device`` into Numba's disk cache, the module jitted as :func:`numba_namespace` jits it for
    :class:`NumbaCudaBackend` (``program_names``: the program's functions, ``backend_names``:
    the backend's)."""
    from numba import cuda

    if digest not in _helper_namespaces:
        cuda.select_device(int(device))
        namespace = import_generated_again(digest).__dict__
        jit_generated(namespace, program_names, backend_names, cuda_device_function,
                      lambda namespace_, names: _jit_entries(cuda, namespace_, names))
        _helper_namespaces[digest] = namespace
    namespace = _helper_namespaces[digest]
    for name, kinds in kernels.items():
        namespace[name].kernel.compile(tuple(numba_type(kind) for kind in kinds))


def numba_type(kind: str):
    """Numba's type of a launch argument of portable type ``kind``, as this backend passes it:
    C-contiguous float64 and int64 arrays, Python ints and floats, a NumPy uint64."""
    from numba.core import types

    arrays = {"floats": (types.float64, 1), "points": (types.float64, 2), "ints": (types.int64, 1),
              "int_table": (types.int64, 2)}
    if kind in arrays:
        return types.Array(*arrays[kind], "C")
    return {"int": types.int64, "float": types.float64, "u64": types.uint64, "bool": types.boolean}[kind]


class _CudaDevice:
    """The device adapter of :class:`~ndpack.backends.prototypes.DevicePrototypes` for one shape.

    Kernels and copies queue on one stream; a fetch copies into pinned buffers through the driver
    call itself, because slicing a device array costs tens of microseconds in numba-cuda.
    """

    DTYPES = {"float": np.float64, "point": np.float64, "index": np.int64}

    def __init__(self, backend, shape):
        self.backend, self.cuda = backend, backend.cuda
        self.namespace, self.params, self.h = backend._kernels(shape)
        self.walks = backend._walks(shape)
        self.stream = self.cuda.stream()
        self._staging = {}  # (slot, dtype, row shape) -> pinned host array that fetch copies into
        import numba

        if numba.config.ENABLE_CUDASIM:  # the simulator copies whole arrays: give it slices
            self._device_to_host = self._memset = self._deallocations = None
        else:
            from numba.cuda.cudadrv.driver import device_memset, device_to_host

            self._device_to_host, self._memset = device_to_host, device_memset
            # numba-cuda frees device memory in batches, every eleventh free by default, and a free
            # waits for the whole device: a batch falling between a round's launches stalls it.
            # The store frees its scratch arrays where the stream is idle anyway (_idle).
            self._deallocations = self.cuda.current_context().deallocations

    def upload(self, host, kind):
        host = np.ascontiguousarray(host, dtype=self.DTYPES[kind])
        if host.ndim == 0:
            return self.cuda.to_device(host, stream=self.stream)
        array = self.cuda.device_array(host.shape, dtype=host.dtype, stream=self.stream)
        _copy_rows(array, 0, host, len(host), self.stream)
        return array

    def empty(self, shape, kind):
        if kind == "point":
            shape = (shape, self.namespace["D"])
        return self.cuda.device_array(shape, dtype=self.DTYPES[kind], stream=self.stream)

    def fill(self, array, value):
        if value == 0 and self._memset is not None:  # no host array, no copy: a launch on the stream
            self._memset(array, 0, array.nbytes, stream=self.stream)
        else:
            array.copy_to_device(np.full(array.shape, value, dtype=array.dtype), stream=self.stream)

    def grow(self, array, rows, kind):
        longer = self.empty(rows, kind)
        _copy_rows(longer, 0, array, len(array), self.stream)
        return longer

    def write(self, array, start, host, kind):
        _copy_rows(array, start, np.ascontiguousarray(host, dtype=self.DTYPES[kind]), len(host), self.stream)

    def fetch(self, *pairs):
        staged = []
        for slot, (array, count) in enumerate(pairs):
            key = (slot, array.dtype, array.shape[1:])
            if key not in self._staging or len(self._staging[key]) < count:
                rows = staging_rows(len(self._staging[key]) if key in self._staging else 0, count)
                self._staging[key] = self.cuda.pinned_array((rows, *array.shape[1:]), dtype=array.dtype)
            buffer = self._staging[key]
            if count and self._device_to_host is not None:
                self._device_to_host(buffer, array, buffer[:count].nbytes, stream=self.stream)
            elif count:
                array[:count].copy_to_host(buffer[:count], stream=self.stream)
            staged.append((buffer, count))
        self._idle()
        return [buffer[:count].copy() for buffer, count in staged]

    def synchronize(self):
        self._idle()

    def _idle(self):
        """Wait for the stream, then free the arrays that died meanwhile: the device has nothing
        to finish first. In numba-cuda's batches the armadillo at 100,000 took 0.91-0.97 s in its
        rounds, with batches never freed 0.69-0.84 s (``bash bench/gpu_issue48_step11.sh deallocs``);
        freed here, 0.77-0.81 s against 0.81-0.87 s in turns (``... flush``; H100s)."""
        self.stream.synchronize()
        if self._deallocations is not None:
            self._deallocations.clear()

    def launch(self, name, threads, *args, lanes=1, most=None):
        """``threads`` threads of kernel ``name``, ``lanes`` of them per item. A move of more than one
        lane per item and at most ``most`` items (default the backend's ``cooperative_most``), where
        the shape walks a tree, runs a block of ``LANES`` threads per item, which walk together
        (numba_cuda_lanes); otherwise the first lane of each item works and the rest idle."""
        items = threads // lanes
        most = self.backend.cooperative_most if most is None else most
        if name == "move_ids" and lanes > 1 and 0 < items <= most and self.walks:
            self.backend._launch(self.namespace[name], items, *args, stream=self.stream, threads=LANES,
                                 shared=shared_bytes(), blocks=items)
            return
        block = self.backend.move_block if name == "move_ids" else THREADS_PER_BLOCK
        self.backend._launch(self.namespace[name], threads, *args, stream=self.stream, threads=block)

    def spheres(self, centers, radii):
        return self.backend._device_spheres(centers, radii)


def _write_rows(centers, radii, start, host_centers, host_radii):
    _copy_rows(centers, start, host_centers, len(host_radii))
    _copy_rows(radii, start, host_radii, len(host_radii))


def _keep_rows(new_centers, new_radii, old_centers, old_radii, count):
    _copy_rows(new_centers, 0, old_centers, count)
    _copy_rows(new_radii, 0, old_radii, count)


def _copy_rows(target, start, source, count, stream=0):
    """``target[start:start + count] = source[:count]`` by one driver call at a byte offset, ``source``
    a host array or a device array: numba-cuda's own copy needs the rows as a slice of ``target``, and
    a slice (a view and its checks) cost 94 us each in a profiled packing of the armadillo at 100,000,
    1,564 of them (``bench/results/launches_h100_numba_cuda_issue48_step13.txt``). Asynchronous on
    ``stream``; else the driver's synchronous copy, as numba-cuda's without a stream. ``target`` (n, ...)
    and ``source`` C-contiguous of one dtype and row (a host ``source`` is made so). In the simulator,
    whose arrays have no device address, numba-cuda's copy of the slice."""
    import numba
    from numba.cuda.cudadrv import driver

    if count <= 0:
        return
    if numba.config.ENABLE_CUDASIM:
        if not hasattr(source, "copy_to_host"):  # a host source
            source = np.ascontiguousarray(source, dtype=target.dtype)
        target[start : start + count].copy_to_device(source[:count], stream=stream)
        return
    row = target.strides[0]
    address = driver.device_pointer(target) + start * row
    handle = (driver._stream_handle(stream),) if stream else ()
    api = driver.driver
    if driver.is_device_memory(source):
        copy = api.cuMemcpyDtoDAsync if stream else api.cuMemcpyDtoD
        copy(address, driver.device_pointer(source), count * row, *handle)
    else:
        source = np.ascontiguousarray(source, dtype=target.dtype)
        copy = api.cuMemcpyHtoDAsync if stream else api.cuMemcpyHtoD
        copy(address, driver.host_pointer(source, readonly=True), count * row, *handle)


def _f64(array):
    return np.ascontiguousarray(array, dtype=np.float64)
