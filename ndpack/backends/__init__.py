"""Backends that run the packing driver's hot loops, chosen at runtime.

========== ======================================== ==============================
name       runs on                                  install
========== ======================================== ==============================
numpy      CPU, one thread (the reference)          always there
numba      CPU, all cores (``prange``)              always there (a dependency)
numba-cuda one NVIDIA GPU (or the CUDA simulator)   ``pip install "ndpack[cuda]"``
warp       ``cpu`` or ``cuda:N`` (NVIDIA Warp)      ``pip install "ndpack[warp]"``
========== ======================================== ==============================

Which one runs, first match wins:

1. the ``backend=`` (and ``device=``) argument of :func:`ndpack.pack`;
2. the innermost ``with ndpack.backends.use(...)`` block;
3. the ``NDPACK_BACKEND`` environment variable (a name, or ``name:device`` such as ``warp:cuda:1``);
4. the fastest that works here and can run the shape: a GPU backend where a CUDA driver and
   device work (warp, then numba-cuda), else numba, else numpy. A shape with a NumPy-only
   plug-in falls back to numpy here; asked for by name, a compiled backend refuses it.

Design rules: importing :mod:`ndpack` imports no backend framework; each backend module is
imported only when it is asked for, and a missing one says how to install it.
"""

from __future__ import annotations

import contextlib
import contextvars
import ctypes.util
import importlib
import os

from ..errors import BackendError
from ..kernels.compiled import has_kernel
from .base import Backend

#: name -> (module, class, pip install hint)
_KNOWN = {
    "numpy": ("ndpack.backends.numpy_backend", "NumpyBackend", None),
    "numba": ("ndpack.backends.numba_backend", "NumbaBackend", "pip install numba"),
    "numba-cuda": ("ndpack.backends.numba_cuda_backend", "NumbaCudaBackend", 'pip install "ndpack[cuda]"'),
    "warp": ("ndpack.backends.warp_backend", "WarpBackend", 'pip install "ndpack[warp]"'),
}
#: The order tried when nothing is asked for: fastest first.
_PREFERENCE = ("warp", "numba-cuda", "numba", "numpy")
_GPU = ("warp", "numba-cuda")

_instances: dict[tuple, Backend] = {}
_chosen: contextvars.ContextVar = contextvars.ContextVar("ndpack_backend", default=None)


def names() -> list[str]:
    """Names of every backend ndpack knows, installed or not."""
    return list(_KNOWN)


def _parse(spec: str) -> tuple[str, str | None]:
    """``"warp:cuda:1"`` -> ``("warp", "cuda:1")``; ``"numba"`` -> ``("numba", None)``."""
    name, _, device = spec.strip().lower().partition(":")
    return name, device or None


def _create(name: str, device=None, **options) -> Backend:
    if name not in _KNOWN:
        raise BackendError(f"unknown backend {name!r}; choose one of {', '.join(_KNOWN)}")
    key = (name, device, tuple(sorted(options.items())))
    if key not in _instances:
        module, cls, hint = _KNOWN[name]
        if name in ("numpy", "numba") and device not in (None, "cpu"):
            raise BackendError(f"backend {name!r} runs on the CPU only, not on device {device!r}")
        kwargs = dict(options)
        if device is not None and name == "warp":
            kwargs["device"] = device
        if device is not None and name == "numba-cuda":
            number = str(device).removeprefix("cuda:").removeprefix("cuda")
            if not number.isdigit():
                raise BackendError(f"numba-cuda needs a CUDA device such as 'cuda:0', got {device!r}")
            kwargs["device"] = int(number)
        try:  # the backends import their GPU package when made, not when their module loads
            _instances[key] = getattr(importlib.import_module(module), cls)(**kwargs)
        except ImportError as error:
            raise BackendError(f"backend {name!r} is not installed ({error}); {hint}") from error
    return _instances[key]


def get_backend(backend: str | Backend | None = None, device=None, shape=None, **options) -> Backend:
    """Resolve a backend by the rules in this module's docstring.

    Parameters
    ----------
    backend : str, Backend or None
        A name (``"numba"``, ``"warp:cuda:0"``), an instance, or None for the rules 2-4.
    device : str or int, optional
        ``"cpu"``, ``"cuda"``, ``"cuda:N"`` (or N) for the GPU-capable backends.
    shape : Oracle, optional
        When choosing automatically, skip backends that cannot compile this shape.
    **options
        Passed to the backend's constructor (for example ``precision="float32"`` for warp).

    Raises
    ------
    BackendError
        For an unknown name, a backend that is not installed or cannot run here.
    """
    if isinstance(backend, Backend):
        return backend
    if backend is None and device is None and not options:
        backend = _chosen.get()
        if isinstance(backend, Backend):
            return backend
    if backend is None:
        backend = os.environ.get("NDPACK_BACKEND") or None
    if backend is None:
        return _fastest(shape, device, **options)
    name, spec_device = _parse(backend)
    return _create(name, device if device is not None else spec_device, **options)


def _cuda_driver_present() -> bool:
    """Whether a CUDA driver library is installed: checked without importing any GPU framework."""
    return ctypes.util.find_library("cuda") is not None


def _fastest(shape, device, **options) -> Backend:
    gpu = _cuda_driver_present() and device != "cpu"
    wants_gpu = device is not None and str(device).lower() != "cpu"
    why_not = {}  # GPU backend -> why it cannot run here, for a device asked for in vain
    for name in _PREFERENCE:
        if wants_gpu and name not in _GPU:
            break
        if name in _GPU and not gpu:
            why_not[name] = "no CUDA driver on this machine"
            continue
        if name != "numpy" and shape is not None and not has_kernel(shape):
            why_not[name] = "the shape has no compiled kernel (a NumPy-only plug-in)"
            continue
        if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1" and name == "numba-cuda":
            why_not[name] = "NUMBA_ENABLE_CUDASIM=1 (the simulator, not a device)"
            continue  # the simulator works but is far slower than the CPU backends
        try:
            return _create(name, device if name in _GPU else None, **(options if name == "warp" else {}))
        except Exception as error:  # noqa: BLE001 - a missing or broken GPU stack must not stop a CPU packing
            why_not[name] = str(error).split("\n")[0]
            continue
    if wants_gpu:  # a device asked for is never dropped in silence: the CPU backends would ignore it
        reasons = "; ".join(f"{name}: {why}" for name, why in why_not.items())
        raise BackendError(f"device {device!r} asked for, but no GPU backend can run here ({reasons}); leave out "
                           f"the device, or give 'cpu', to pack on the CPU")
    return _create("numpy")


@contextlib.contextmanager
def use(backend: str | Backend, device=None, **options):
    """Run the packings inside the block on ``backend`` unless they ask for another.

    Examples
    --------
    >>> with ndpack.backends.use("numba"):          # doctest: +SKIP
    ...     packing = ndpack.pack(shape, n=10_000)
    """
    token = _chosen.set(get_backend(backend, device=device, **options))
    try:
        yield _chosen.get()
    finally:
        _chosen.reset(token)


def available() -> dict[str, str]:
    """Each known backend mapped to ``"ok"`` (with its device) or the reason it cannot run here."""
    status = {}
    for name in _KNOWN:
        try:
            backend = _create(name)
            device = getattr(backend, "device", None)
            status[name] = "ok" if device is None else f"ok ({device})"
        except BackendError as error:
            status[name] = str(error)
        except Exception as error:  # noqa: BLE001 - report, never crash, when listing
            status[name] = f"fails to start: {type(error).__name__}: {error}"
    return status


__all__ = ["Backend", "available", "get_backend", "names", "use"]
