"""Test defaults: packings run on the NumPy reference unless a test asks for another backend,
so that the suite does not pay a compile for every shape. Backend tests pass ``backend=``."""

import pytest


@pytest.fixture(autouse=True)
def _reference_backend(monkeypatch):
    monkeypatch.setenv("NDPACK_BACKEND", "numpy")
