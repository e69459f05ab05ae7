"""numba-cuda's replayed launches (numba_cuda_launch.Replay), against a stand-in for numba-cuda's
launch internals: what is prepared again, what falls back to the dispatcher. (On a GPU the device
store's tests and the GPU scripts' same-spheres checks run the real thing.)"""

import numpy as np

from ndpack.backends.numba_cuda_launch import Replay


class DeviceArray:
    def __init__(self, rows, dtype="float64"):
        self.shape, self.dtype = (rows,), dtype


class Kernel:
    """A compiled kernel as numba-cuda 0.30 has it, recording what it prepares."""

    def __init__(self, types, debug=False):
        self.argument_types, self.debug, self.cooperative = types, debug, False
        self.prepared = []
        outer = self

        class Library:
            @staticmethod
            def get_cufunc():
                class Function:
                    kernel = ("function", id(outer))
                return Function

        self._codelibrary = Library

    def _prepare_args(self, ty, value, stream, written_back, out):
        self.prepared.append(value)
        if isinstance(value, np.ndarray):  # a host array: numba-cuda copies it, and back
            written_back.append(lambda: None)
        out.extend([id(value), ty] if hasattr(value, "shape") else [value])


class Dispatcher:
    """A numba-cuda dispatcher: ``d[blocks, threads, stream, shared](*args)``, one compiled kernel."""

    def __init__(self, kernel):
        self.kernel, self.dispatched = kernel, []
        self.overloads = {tuple(kernel.argument_types): kernel}

    def __getitem__(self, configuration):
        return lambda *args: self.dispatched.append((configuration, args))


class Api:
    CUDA_CORE_GE_1_0 = True
    launched = []

    @staticmethod
    def typeof(value):
        if hasattr(value, "shape"):
            return f"array({value.dtype})"
        return type(value).__name__

    @staticmethod
    def core_stream(stream):
        return ("core", stream)

    @staticmethod
    def LaunchConfig(**config):
        return config

    @classmethod
    def launch(cls, stream, config, function, *flat):
        cls.launched.append((stream, config, function, flat))


def test_a_kernel_s_first_launch_goes_through_its_dispatcher_and_the_next_are_replayed():
    Api.launched = []
    kernel = Kernel(("array(float64)", "array(float64)", "int", "float"))
    dispatcher = Dispatcher(kernel)
    replay = Replay(Api)
    points, out = DeviceArray(10), DeviceArray(10)
    replay.launch(dispatcher, 4, 256, "stream", (points, out, 10, 0.5))
    assert len(dispatcher.dispatched) == 1 and Api.launched == []
    replay.launch(dispatcher, 4, 256, "stream", (points, out, 10, 0.5))
    assert kernel.prepared == [points, out, 10, 0.5]  # everything, once
    other = DeviceArray(12)
    replay.launch(dispatcher, 5, 256, "stream", (points, other, 12, 0.25))
    # The same array is not prepared again; a new one and the scalars are.
    assert kernel.prepared[4:] == [other, 12, 0.25]
    stream, config, function, flat = Api.launched[-1]
    assert stream == ("core", "stream") and function == ("function", id(kernel))
    assert config == dict(grid=(5, 1, 1), block=(256, 1, 1), shmem_size=0, is_cooperative=False)
    assert flat == (id(points), "array(float64)", id(other), "array(float64)", 12, 0.25)
    assert len(dispatcher.dispatched) == 1


def test_arguments_that_do_not_fit_the_kernel_go_through_the_dispatcher():
    Api.launched = []
    kernel = Kernel(("array(float64)", "int"))
    dispatcher = Dispatcher(kernel)
    replay = Replay(Api)
    points = DeviceArray(3)
    replay.launch(dispatcher, 1, 32, 0, (points, 3))
    replay.launch(dispatcher, 1, 32, 0, (DeviceArray(3, "int64"), 3))  # another type: another overload
    replay.launch(dispatcher, 1, 32, 0, (np.zeros(3), 3))  # a host array (typed as the kernel's: copied)
    assert len(dispatcher.dispatched) == 3 and Api.launched == []
    replay.launch(dispatcher, 1, 32, 0, (points, 3))  # and the recorded state is the last good launch's
    assert Api.launched[-1][3] == (id(points), "array(float64)", 3)


def test_without_numba_cuda_s_internals_every_launch_goes_through_the_dispatcher():
    Api.launched = []
    kernel = Kernel(("int",))
    del kernel._codelibrary  # another numba-cuda
    dispatcher = Dispatcher(kernel)
    replay = Replay(Api)
    for _ in range(3):
        replay.launch(dispatcher, 1, 32, 0, (1,))
    debug = Dispatcher(Kernel(("int",), debug=True))  # a debug kernel checks its errors after the launch
    for _ in range(2):
        replay.launch(debug, 1, 32, 0, (1,))
    assert len(dispatcher.dispatched) == 3 and len(debug.dispatched) == 2 and Api.launched == []


def test_dynamic_shared_memory_and_streams_are_passed():
    Api.launched = []
    dispatcher = Dispatcher(Kernel(("int",)))
    replay = Replay(Api)
    replay.launch(dispatcher, 7, 64, "s1", (1,), shared=4096)
    assert dispatcher.dispatched[0][0] == (7, 64, "s1", 4096)
    replay.launch(dispatcher, 7, 64, "s2", (1,), shared=4096)
    stream, config, _, _ = Api.launched[-1]
    assert stream == ("core", "s2") and config["shmem_size"] == 4096 and config["grid"] == (7, 1, 1)
