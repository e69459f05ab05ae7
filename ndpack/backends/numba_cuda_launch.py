"""numba-cuda's kernel launches, their arguments prepared once and again only where they change.

A launch through numba-cuda's dispatcher (``kernel[grid, block, stream](*args)``) types every
argument, flattens each device array into its pointer, shape and strides in Python, and builds a
launch configuration and a stream object: about 0.3 ms of the host's time a launch (numba-cuda
0.30, an H100's host, profiled), and a packing of the armadillo at 100,000 spheres makes about
1,000 launches in its rounds, during which the GPU waited 0.20 s of its 0.87 s idle
(``bench/gpu_timeline.py``, ``bash bench/gpu_issue48_step13.sh timeline``). As Warp's recorded
launches do (``warp_backend._WarpDevice._replay``), a :class:`Replay` keeps each kernel's compiled
form and its last flattened arguments, and prepares again only the arguments that are not the last
launch's objects (and the scalars), checking their types against the kernel's.

It reaches into numba-cuda's own launch (``_Kernel._prepare_args``, ``_codelibrary``,
``argument_types``, and the ``launch``, ``LaunchConfig`` and ``CUDA_CORE_GE_1_0`` its dispatcher
module imports), measured too slow for this hot path; where any of that is missing, or an argument
would be copied to the device (a host array), the kernel launches through the dispatcher.
"""

from __future__ import annotations

#: Not yet launched (a kernel's first launch goes through the dispatcher, which compiles it).
_FIRST = object()


class Replay:
    """Launches of numba-cuda kernels, each after the first from its recorded arguments.

    ``numba_cuda`` (tests): a namespace with ``launch``, ``LaunchConfig``, ``CUDA_CORE_GE_1_0``,
    ``typeof`` (a value's argument type) and ``core_stream`` (a numba stream's cuda.core stream);
    by default numba-cuda's own.
    """

    def __init__(self, numba_cuda=None):
        self._api = numba_cuda
        self._recorded: dict = {}  # dispatcher -> _Recorded, or None where it launches through the dispatcher
        self._streams: dict = {}  # id(numba stream) -> (numba stream, cuda.core stream)

    def launch(self, dispatcher, blocks: int, threads: int, stream, args, shared: int = 0) -> None:
        """``dispatcher[blocks, threads, stream, shared](*args)``."""
        recorded = self._recorded.get(dispatcher, _FIRST)
        if recorded is _FIRST:
            dispatcher[blocks, threads, stream, shared](*args)
            self._recorded[dispatcher] = self._record(dispatcher, args)
            return
        if recorded is None or not recorded.launch(blocks, threads, self._core_stream(stream), stream, shared, args):
            dispatcher[blocks, threads, stream, shared](*args)

    def _api_or_default(self):
        if self._api is None:
            from numba.cuda import dispatcher as module
            from numba.cuda.cudadrv import driver
            from numba.cuda.typing.typeof import Purpose, typeof

            class Api:
                launch, LaunchConfig = module.launch, module.LaunchConfig
                CUDA_CORE_GE_1_0 = module.CUDA_CORE_GE_1_0
                core_stream = staticmethod(driver._to_core_stream)

                @staticmethod
                def typeof(value):
                    return typeof(value, Purpose.argument)

            self._api = Api
        return self._api

    def _record(self, dispatcher, args):
        """The kernel ``dispatcher`` compiled for ``args``, ready to replay, or None."""
        try:
            api = self._api_or_default()
            kernel = dispatcher.overloads.get(tuple(api.typeof(value) for value in args))
            if kernel is None or getattr(kernel, "debug", False):
                return None
            return _Recorded(api, kernel, kernel._codelibrary.get_cufunc().kernel, tuple(kernel.argument_types))
        except (AttributeError, ImportError, TypeError, ValueError):
            return None  # another numba-cuda: its dispatcher launches

    def _core_stream(self, stream):
        key = id(stream)
        found = self._streams.get(key)
        if found is None or found[0] is not stream:
            found = (stream, self._api_or_default().core_stream(stream))
            self._streams[key] = found
        return found[1]


class _Recorded:
    """One kernel's compiled form and its last launch's flattened arguments."""

    def __init__(self, api, kernel, function, types):
        self.api, self.kernel, self.function, self.types = api, kernel, function, types
        self.last: list = [_FIRST] * len(types)  # the last launch's argument objects
        self.parts: list = [()] * len(types)  # and each one's flattened values

    def launch(self, blocks, threads, core_stream, stream, shared, args) -> bool:
        """Launch with ``args``; False (nothing launched) where one of them does not fit the kernel."""
        if len(args) != len(self.types):
            return False
        parts = list(self.parts)
        for index, value in enumerate(args):
            if value is self.last[index] and hasattr(value, "shape"):
                continue  # the same device array: the same pointer, shape and strides
            if self.api.typeof(value) != self.types[index]:
                return False
            written_back, part = [], []
            self.kernel._prepare_args(self.types[index], value, stream, written_back, part)
            if written_back:  # a host array, copied to the device (and back): the dispatcher's to do
                return False
            parts[index] = part
        self.parts, self.last = parts, list(args)
        flat = [value for part in parts for value in part]
        cooperative = {"is_cooperative" if self.api.CUDA_CORE_GE_1_0 else "cooperative_launch":
                       bool(getattr(self.kernel, "cooperative", False))}
        config = self.api.LaunchConfig(grid=(blocks, 1, 1), block=(threads, 1, 1), shmem_size=shared, **cooperative)
        self.api.launch(core_stream, config, self.function, *flat)
        return True
