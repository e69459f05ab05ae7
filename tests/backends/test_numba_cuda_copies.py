"""numba-cuda's copies into part of a device array (numba_cuda_backend._copy_rows), against a stand-in
for numba-cuda's driver: the byte offsets and sizes, and which copy (host or device source, on a
stream or not). (On a GPU the device store's tests and the GPU scripts' same-spheres checks run
the real driver.)"""

import numpy as np
import pytest

from ndpack.backends import numba_cuda_backend

pytest.importorskip("numba.cuda.cudadrv.driver")
numba = pytest.importorskip("numba")
pytestmark = pytest.mark.skipif(bool(numba.config.ENABLE_CUDASIM),
                                reason="the simulator keeps numba-cuda's own copies; these are the driver's")


class Device:
    """A device array's stand-in: its address, row stride and dtype, as numba-cuda has them."""

    __cuda_memory__ = True

    def __init__(self, address, rows, width=None, dtype=np.float64):
        self.address, self.dtype = address, np.dtype(dtype)
        self.shape = (rows,) if width is None else (rows, width)
        self.strides = (self.dtype.itemsize * (width or 1),) + ((self.dtype.itemsize,) if width else ())


class Api:
    """The driver's copies, recorded."""

    def __init__(self):
        self.calls = []

    def __getattr__(self, name):
        if not name.startswith("cuMemcpy"):
            raise AttributeError(name)
        return lambda *args: self.calls.append((name, *args))


@pytest.fixture
def driver(monkeypatch):
    from numba.cuda.cudadrv import driver as real

    api = Api()
    monkeypatch.setattr(real, "driver", api)
    monkeypatch.setattr(real, "device_pointer", lambda array: array.address)
    monkeypatch.setattr(real, "is_device_memory", lambda obj: isinstance(obj, Device))
    monkeypatch.setattr(real, "host_pointer", lambda array, readonly=False: ("host", array.dtype, array.tolist()))
    monkeypatch.setattr(real, "_stream_handle", lambda stream: ("stream", stream))
    return api


def test_host_rows_go_to_their_byte_offset_on_the_stream(driver):
    target = Device(1000, rows=10, width=3)  # 24 bytes a row
    rows = np.arange(6.0).reshape(2, 3)
    numba_cuda_backend._copy_rows(target, 4, rows, 2, stream=7)
    (name, address, source, size, stream), = driver.calls
    assert (name, address, size, stream) == ("cuMemcpyHtoDAsync", 1000 + 4 * 24, 2 * 24, ("stream", 7))
    assert source == ("host", np.dtype(np.float64), rows.tolist())


def test_a_host_source_of_another_dtype_is_converted_first(driver):
    target = Device(0, rows=8, dtype=np.int64)
    numba_cuda_backend._copy_rows(target, 1, [3, 4, 5], 3)
    (name, address, source, size), = driver.calls  # no stream: the driver's synchronous copy
    assert (name, address, source, size) == ("cuMemcpyHtoD", 8, ("host", np.dtype(np.int64), [3, 4, 5]), 24)


def test_device_rows_are_copied_on_the_device_and_nothing_for_no_rows(driver):
    target, source = Device(5000, rows=20, width=2), Device(9000, rows=7, width=2)
    numba_cuda_backend._copy_rows(target, 0, source, 0, stream=3)
    assert driver.calls == []
    numba_cuda_backend._copy_rows(target, 0, source, 5, stream=3)
    numba_cuda_backend._copy_rows(target, 10, source, 5)
    assert driver.calls == [("cuMemcpyDtoDAsync", 5000, 9000, 5 * 16, ("stream", 3)),
                            ("cuMemcpyDtoD", 5000 + 10 * 16, 9000, 5 * 16)]
