"""Backends that run the packing driver's hot loops, chosen at runtime.

Design rules: importing :mod:`ndpack` imports no backend framework; each backend module is
imported only when it is asked for, and a missing one says how to install it.
"""

from __future__ import annotations

import importlib
import os

from ..errors import BackendError
from .base import Backend

#: name -> (module, class, pip install hint)
_KNOWN = {
    "numpy": ("ndpack.backends.numpy_backend", "NumpyBackend", None),
    "numba": ("ndpack.backends.numba_backend", "NumbaBackend", "pip install numba"),
}

_instances: dict[str, Backend] = {}


def names() -> list[str]:
    """Names of every backend ndpack knows, installed or not."""
    return list(_KNOWN)


def get_backend(backend: str | Backend | None = None) -> Backend:
    """Resolve ``backend``: an instance, a name, or None for ``$NDPACK_BACKEND`` or the default.

    Raises
    ------
    BackendError
        For an unknown name or a backend whose framework is not installed.
    """
    if isinstance(backend, Backend):
        return backend
    name = backend or os.environ.get("NDPACK_BACKEND") or "numpy"
    name = name.strip().lower()
    if name not in _KNOWN:
        raise BackendError(f"unknown backend {name!r}; choose one of {', '.join(_KNOWN)}")
    if name not in _instances:
        module, cls, hint = _KNOWN[name]
        try:
            _instances[name] = getattr(importlib.import_module(module), cls)()
        except ImportError as error:
            raise BackendError(f"backend {name!r} is not installed ({error}); {hint}") from error
    return _instances[name]


def available() -> dict[str, str]:
    """Each known backend mapped to ``"ok"`` or the reason it cannot run here."""
    status = {}
    for name in _KNOWN:
        try:
            get_backend(name)
            status[name] = "ok"
        except BackendError as error:
            status[name] = str(error)
    return status


__all__ = ["Backend", "available", "get_backend", "names"]
