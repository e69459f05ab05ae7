"""The NVIDIA Warp backend: one Warp thread per prototype, on ``cpu`` or ``cuda:N``.

The tape interpreter of a dimension (:mod:`ndpack.kernels.tape`) is printed in Warp's dialect and
written, with the kernels of :mod:`ndpack.backends.warp_kernels` and those written once for every
compiled backend (:mod:`ndpack.backends.index_kernels`, :mod:`ndpack.backends.store_kernels`), into
one generated module (see :func:`ndpack.kernels.compile.warp_module`); Warp compiles it once per
machine, for every shape of built-ins, and keeps the binary. A shape is its numbers, copied to the
device once. The inserted spheres live on the device
(:class:`~ndpack.backends.device_spheres.DeviceSpheres`), and during a packing so do the prototypes
(:class:`~ndpack.backends.prototypes.DevicePrototypes`, through :class:`_WarpDevice`). On a GPU, a
launch that moves few prototypes in a mesh (or outline) gives each a block of 32 threads that walk
its tree together, from a second module (:mod:`ndpack.backends.warp_lanes`; the backend's
``cooperative_most`` and ``cooperative_converge_most``, 0 for never).

Precision: float64 by default. ``precision="float32"`` runs the kernels in float32 (faster on GPUs
without full float64 rate); clearances are then accurate to about 1e-7 of the shape's size, so the
driver shrinks radii by :attr:`WarpBackend.margin` of the size, and the packing is still verified
(and repaired) in float64 before it is returned.
"""

from __future__ import annotations

import weakref
from pathlib import Path

import numpy as np

from ..errors import BackendError
from ..kernels.compile import warp_module
from ..kernels.compiled import compiled_program
from ..kernels.portable import render
from ..kernels.tape import interpreter
from .base import Backend, staging_rows, tightened_reach
from .device_spheres import DeviceSpheres
from .kernel_texts import INDEX, MOVE, STORE, portable_text
from .prototypes import SPREAD_MAX, DevicePrototypes, converge_by_move
from .warp_lanes import CONVERGE_MOST, COOPERATIVE_MOST, LANES, SHARE_EVERY, functions_only, has_walk, lanes_text

#: Warp's own kernels, then the move, the sphere index's queries and the store's kernels, written once for
#: every compiled backend (move_kernels.py, index_kernels.py, store_kernels.py).
KERNELS = (Path(__file__).with_name("warp_kernels.py").read_text() + "\n\n"
           + render(portable_text(MOVE, INDEX, STORE), "warp"))
#: Central-difference step as a fraction of the shape's scale, per precision.
FD_STEP = {"float64": 1e-6, "float32": 1e-3}
#: Radius safety margin as a fraction of the shape's scale, per precision.
MARGIN = {"float64": 1e-10, "float32": 2e-6}
#: Threads of a block in a launch of one thread per item (Warp's default).
THREAD_BLOCK = 256
#: The same in a move launch that is not cooperative (the backend's ``move_block``). Blocks of 64, 128
#: and 256 threads moved the armadillo's 100,000 spheres alike on an H200, on Warp and on numba-cuda
#: (whose default is 128): ``bench/gpu_issue48_step15.sh blocks``, ``--variants block-N``.
MOVE_BLOCK = THREAD_BLOCK


class WarpBackend(Backend):
    """NVIDIA Warp kernels.

    Parameters
    ----------
    device : str, optional
        ``"cpu"``, ``"cuda"`` or ``"cuda:N"``; default the first CUDA device, else the CPU.
    precision : {"float64", "float32"}
    """

    name = "warp"

    def __init__(self, device: str | None = None, precision: str = "float64"):
        import warp as wp

        if precision not in FD_STEP:
            raise BackendError(f"precision must be 'float64' or 'float32', got {precision!r}")
        _quiet(wp)
        wp.init()
        if device is None:
            device = "cuda:0" if wp.is_cuda_available() else "cpu"
        try:
            self.device = wp.get_device(device)
        except (ValueError, RuntimeError) as error:
            raise BackendError(f"Warp cannot use device {device!r} ({error}); try 'cpu' or 'cuda:0'") from None
        if self.device.is_cpu and not wp.is_cpu_available():
            raise BackendError("Warp's CPU compiler is not available here; use device='cuda:0' or backend='numba'")
        self.wp = wp
        self.launch_bound = self.device.is_cuda
        # Threads per prototype in a move launch, at most (prototypes.lane_spread); idle ones cost a CPU.
        self.move_spread = SPREAD_MAX if self.launch_bound else 1
        # A move launch of at most this many prototypes walks cooperatively, and a converge of at most
        # cooperative_converge_most points (0: never; see warp_lanes).
        self.cooperative_most = COOPERATIVE_MOST if self.launch_bound else 0
        self.cooperative_converge_most = CONVERGE_MOST if self.launch_bound else 0
        self.cooperative_share = SHARE_EVERY  # rounds between the lanes' agreements (warp_lanes)
        self.move_block = MOVE_BLOCK  # threads of a block in a move launch that is not cooperative
        self.precision = precision
        self.margin = MARGIN[precision]
        self.float = np.float64 if precision == "float64" else np.float32
        self._modules = {}  # id(program) -> (program, module)
        self._lanes = {}  # (id(program), cooperative_share) -> (program, its cooperative module or None)
        self._params = weakref.WeakKeyDictionary()  # shape -> its numbers on the device
        self._spheres = {}

    def __repr__(self):
        return f"<ndpack backend 'warp' on {self.device} ({self.precision})>"

    # ------------------------------------------------------------------ compilation
    def _module(self, shape):
        """The compiled module that runs ``shape``, its numbers on the device and its
        finite-difference step."""
        flat = compiled_program(shape)
        module = self._program_module(flat.program)
        if shape not in self._params:
            params = flat.params
            if self.precision == "float32":
                if params.size > 2**24:  # offsets are floats in the array: float32 counts exactly to 2^24
                    raise BackendError(
                        f"{shape!r} needs {params.size:,} numbers, more than float32 kernels can address; "
                        "use precision='float64'")
                if flat.device_values:
                    params = params.copy()
                    for offset, count, resolve in flat.device_values:
                        params[offset:offset + count] = resolve(self.device)
            self._params[shape] = self._array(params, module.F)
        return module, self._params[shape], self.float(FD_STEP[self.precision] * shape.scale)

    def _program_module(self, program):
        """The backend's kernels and ``program`` as one Warp module, loaded on this device."""
        if id(program) not in self._modules:
            self._modules[id(program)] = (program, warp_module(program, self.precision, KERNELS, self.device))
        return self._modules[id(program)][1]

    def _lanes_module(self, shape):
        """The cooperative move of ``shape``'s program (:mod:`~ndpack.backends.warp_lanes`), in a
        module of its own compiled for blocks of ``LANES``; None where the program walks no tree."""
        program = compiled_program(shape).program
        key = (id(program), self.cooperative_share)
        if key not in self._lanes:
            module = None
            source = program.source("warp", self.precision)
            if has_walk(source):
                kernels = functions_only(KERNELS) + "\n\n" + lanes_text(source + "\n\n" + KERNELS,
                                                                         share=self.cooperative_share)
                module = warp_module(program, self.precision, kernels, self.device, block_dim=LANES,
                                     what=" (cooperative moves)")
            self._lanes[key] = (program, module)
        return self._lanes[key][1]

    def _geometry(self, dim):
        """The shape-free kernels (near_spheres, touched) for dimension ``dim``: those of the
        tape interpreter's module, which the shapes of built-ins share."""
        return self._program_module(interpreter(dim))

    # ------------------------------------------------------------------ arrays
    def _array(self, host, dtype):
        """A device copy of ``host`` as Warp ``dtype`` (int32 tables, else the float type)."""
        values = np.ascontiguousarray(host, dtype=np.int32 if dtype is self.wp.int32 else self.float)
        return self.wp.array(values, dtype=dtype, device=self.device)

    def _points(self, module, host):
        return self._array(host, module.VecD)

    def _sphere_mirror(self, module, dim):
        if dim not in self._spheres:
            wp, device = self.wp, self.device

            def empty(capacity, d):
                return (wp.empty(capacity, dtype=module.VecD, device=device),
                        wp.empty(capacity, dtype=module.F, device=device))

            def write(centers, radii, start, host_centers, host_radii):
                wp.copy(centers, self._array(host_centers, module.VecD), dest_offset=start)
                wp.copy(radii, self._array(host_radii, module.F), dest_offset=start)

            def keep(new_centers, new_radii, old_centers, old_radii, count):
                wp.copy(new_centers, old_centers, count=count)
                wp.copy(new_radii, old_radii, count=count)

            self._spheres[dim] = DeviceSpheres(empty, write, keep, lambda array, count: array[:count])
        return self._spheres[dim]

    def _device_spheres(self, module, centers, radii):
        """Device copies of the spheres; one far away stands in for none, so no array is empty."""
        if len(centers) == 0:
            centers, radii = np.full((1, module.D), 1e30), np.zeros(1)
        return self._sphere_mirror(module, module.D).sync(_f64(centers), _f64(radii))

    def _spheres_and_table(self, module, centers, radii, neighbours):
        d_centers, d_radii = self._device_spheres(module, centers, radii)
        table = neighbours if neighbours.shape[1] else np.full((len(neighbours), 1), len(centers))
        return d_centers, d_radii, self._array(table, self.wp.int32)

    # ------------------------------------------------------------------ operations
    def _free_space(self, shape, points, centers, radii, neighbours, directions):
        module, params, h = self._module(shape)
        d_centers, d_radii, table = self._spheres_and_table(module, centers, radii, neighbours)
        out = self.wp.empty(len(points), dtype=module.F, device=self.device)
        out_direction = self.wp.empty(len(points) if directions else 0, dtype=module.VecD, device=self.device)
        if len(points):
            self.wp.launch(module.clearance_all, dim=len(points), device=self.device, inputs=[
                self._points(module, points), params, d_centers, d_radii, table, h, out, out_direction,
            ])
        direction = out_direction.numpy().reshape(-1, shape.dim).astype(np.float64)
        return out.numpy().astype(np.float64), direction

    def distance(self, shape, points):
        module, params, _ = self._module(shape)
        out = self.wp.empty(len(points), dtype=module.F, device=self.device)
        if len(points):
            self.wp.launch(module.distance_all, dim=len(points), device=self.device,
                           inputs=[self._points(module, points), params, out])
        return out.numpy().astype(np.float64)

    def converge(self, shape, points, cell_lower, cell_upper, centers, radii, neighbours, steps, wall=None,
                 starts=None):
        """The base class's converge, run by the move kernel: see
        :func:`~ndpack.backends.prototypes.converge_by_move`."""
        return converge_by_move(self, _WarpDevice(self, shape), shape, points, cell_lower, cell_upper, centers, radii,
                                neighbours, steps, wall, starts)

    def near_spheres(self, box_lower, box_upper, reach, centers, radii, return_bound=False):
        if return_bound:
            table = self.near_spheres(box_lower, box_upper, reach, centers, radii)
            return table, tightened_reach(box_lower, box_upper, reach, centers, radii, table)
        count = len(box_lower)
        if len(centers) == 0 or count == 0:
            return np.zeros((count, 0), dtype=np.int64)
        module = self._geometry(box_lower.shape[1])
        d_centers, d_radii = self._sphere_mirror(module, module.D).sync(_f64(centers), _f64(radii))
        args = [self._points(module, box_lower), self._points(module, box_upper), self._array(reach, module.F),
                d_centers, d_radii]
        counts = self.wp.empty(count, dtype=self.wp.int32, device=self.device)
        # First pass counts (into a one-column scratch table), second fills a table that fits.
        scratch = self.wp.empty((count, 1), dtype=self.wp.int32, device=self.device)
        self.wp.launch(module.near_all, dim=count, device=self.device, inputs=[*args, counts, scratch])
        width = int(counts.numpy().max())
        out = self._array(np.full((count, max(width, 1)), len(centers)), self.wp.int32)
        if width:
            self.wp.launch(module.near_all, dim=count, device=self.device, inputs=[*args, counts, out])
        return out.numpy()[:, :width].astype(np.int64)

    def prototypes(self, shape, cell_lower, cell_upper, reach, points, clearance, wall=None):
        """The prototypes on this backend's device (see :class:`~ndpack.backends.prototypes.DevicePrototypes`)."""
        return DevicePrototypes(_WarpDevice(self, shape), cell_lower, cell_upper, reach, points, clearance, wall,
                                spread=self.move_spread)

    def touched(self, points, clearance, new_centers, new_radii):
        if len(points) == 0:
            return np.zeros(0, dtype=np.int64)
        module = self._geometry(points.shape[1])
        out = self.wp.empty(len(points), dtype=self.wp.int32, device=self.device)
        self.wp.launch(module.touched_all, dim=len(points), device=self.device, inputs=[
            self._points(module, points), self._array(clearance, module.F),
            self._points(module, new_centers), self._array(new_radii, module.F), out,
        ])
        return out.numpy().astype(np.int64)


class _WarpDevice:
    """The device adapter of :class:`~ndpack.backends.prototypes.DevicePrototypes` for one shape."""

    def __init__(self, backend, shape):
        self.backend, self.wp, self.where = backend, backend.wp, backend.device
        self.module, self.params, self.h = backend._module(shape)
        self.shape = shape
        self.dtypes = {"float": self.module.F, "point": self.module.VecD, "index": self.wp.int32}
        self._staging = {}  # (slot, dtype) -> pinned host array that fetch copies into, and its numpy view
        self._recorded = {}  # (kernel, block size) -> its recorded launch (wp.Launch) and last arguments

    def upload(self, host, kind):
        return self.backend._array(host, self.dtypes[kind])

    def empty(self, shape, kind):
        return self.wp.empty(shape, dtype=self.dtypes[kind], device=self.where)

    def fill(self, array, value):
        array.fill_(value)

    def grow(self, array, rows, kind):
        longer = self.empty(rows, kind)
        if len(array):
            self.wp.copy(longer, array, count=len(array))
        return longer

    def write(self, array, start, host, kind):
        if len(host):
            self.wp.copy(array, self.upload(host, kind), dest_offset=start, count=len(host))

    def fetch(self, *pairs):
        wp = self.wp
        if self.where.is_cpu:
            return [self._host(array[:count].numpy(), array) for array, count in pairs]
        staged = []
        for slot, (array, count) in enumerate(pairs):
            key = (slot, array.dtype)
            if key not in self._staging or self._staging[key][0].shape[0] < count:
                rows = staging_rows(self._staging[key][0].shape[0] if key in self._staging else 0, count)
                buffer = wp.empty(rows, dtype=array.dtype, device="cpu", pinned=True)
                # Its numpy view once: making one costs a fetch more than its copy does.
                self._staging[key] = (buffer, buffer.numpy())
            buffer, view = self._staging[key]
            if count:  # pinned destination: the copies queue behind the kernels, one wait for all
                wp.copy(buffer, array, count=count)
            staged.append((view, count, array))
        wp.synchronize_device(self.where)
        return [self._host(view[:count], array) for view, count, array in staged]

    def _host(self, values, array):
        """A float64 (or int64) copy of fetched ``values`` of the device ``array``."""
        # A fetched prefix may run past the answers into uninitialised rows: never read, so
        # their casts may not warn.
        with np.errstate(invalid="ignore"):
            if array.dtype is self.module.VecD:
                return values.astype(np.float64).reshape(-1, self.module.D)
            return values.astype(np.int64 if array.dtype is self.wp.int32 else np.float64)

    def synchronize(self):
        self.wp.synchronize_device(self.where)

    def launch(self, name, threads, *args, lanes=1, most=None):
        """``threads`` threads of kernel ``name``, ``lanes`` of them per item. A launch of more than
        one lane per item and at most ``most`` items (default the backend's ``cooperative_most``)
        runs the cooperative kernel ``name_lanes`` instead where the shape has one: a block of
        ``LANES`` per item."""
        if not threads:
            return
        items = threads // lanes
        if lanes > 1 and items <= (self.backend.cooperative_most if most is None else most):
            cooperative = getattr(self.backend._lanes_module(self.shape), name + "_lanes", None)
            if cooperative is not None:
                self._replay(cooperative, [items, LANES], args, LANES)  # a tiled launch: a block per item
                return
        self._replay(getattr(self.module, name), threads, args,
                     self.backend.move_block if name == "move_ids" else THREAD_BLOCK)

    def _replay(self, kernel, dim, args, block_dim=THREAD_BLOCK):
        """Launch ``kernel`` over ``dim`` threads with ``args`` by replaying its recorded launch
        (``wp.Launch``), setting again only the arguments that are not the last launch's objects:
        Warp packs every argument of a plain launch, 57 us for a move's 22 against 13 us for a replay
        that sets 3 and the size (2 cores, ``bench/launch_cost.py``), and a GPU round makes about 24
        launches."""
        recorded = self._recorded.get((kernel, block_dim))
        if recorded is None:
            command = self.wp.launch(kernel, dim=dim, inputs=list(args), device=self.where, block_dim=block_dim,
                                     record_cmd=True)
            self._recorded[(kernel, block_dim)] = (command, list(args))
        else:
            command, last = recorded
            for index, value in enumerate(args):
                if value is not last[index]:
                    command.set_param_at_index(index, value)
                    last[index] = value
            command.set_dim(dim)
        command.launch()

    def spheres(self, centers, radii):
        return self.backend._device_spheres(self.module, centers, radii)


def _quiet(wp):
    """Keep Warp's start-up banner and per-module messages out of the user's output."""
    if hasattr(wp.config, "quiet"):
        wp.config.quiet = True
    else:
        from warp._src.logger import LOG_WARNING  # Warp >= 1.10 replaced quiet with log levels

        wp.config.log_level = max(wp.config.log_level, LOG_WARNING)


def _f64(array):
    return np.ascontiguousarray(array, dtype=np.float64)
