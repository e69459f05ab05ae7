"""numba-cuda's device functions compile once per argument types, not once per constant (issue 48)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from ndpack.kernels.compile import cuda_device_function

pytest.importorskip("numba.cuda")


def pick(x, want):
    if want == 0:
        return x
    return -x


@pytest.fixture
def typing_without_gpu(monkeypatch):
    """Typing and lowering a device function (no NVVM, no GPU): they ask only for a compute capability."""
    import numba

    if numba.config.ENABLE_CUDASIM:
        pytest.skip("the CUDA simulator compiles nothing")
    from numba.cuda import dispatcher

    monkeypatch.setattr(dispatcher, "get_current_device", lambda: SimpleNamespace(compute_capability=(9, 0)))


def calls_with_constants(function) -> list[tuple[str, ...]]:
    """The signatures ``function`` is compiled for when called with the constants 0 and 1."""
    from numba.core import types

    for value in (0, 1):
        function.get_call_template((types.float64, types.IntegerLiteral(value)), {})
    return [tuple(str(t) for t in signature) for signature in function.overloads]


def test_a_constant_argument_compiles_one_copy(typing_without_gpu):
    from numba import cuda

    # numba-cuda's own device function: a copy per constant (what the wrapper is for).
    assert calls_with_constants(cuda.jit(device=True)(pick)) == [("float64", "Literal[int](0)"),
                                                                ("float64", "Literal[int](1)")]
    assert calls_with_constants(cuda_device_function(pick)) == [("float64", "int64")]
