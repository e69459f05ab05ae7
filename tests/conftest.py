"""Test defaults.

- Packings run on the NumPy reference unless a test asks for another backend, so that the suite
  does not pay a compile for every shape. Backend tests pass ``backend=``.
- No silent repair: ``nd.pack`` raises instead of shrinking spheres that fail its final check
  (``NDPACK_ON_INVALID=raise``, inherited by the CLI's subprocesses too), and a
  ``RepairWarning`` is an error (pyproject's ``filterwarnings``). A test that checks a
  validity assertion can therefore fail; the tests of the repair itself ask for it by name.
"""

import pytest


@pytest.fixture(autouse=True)
def _reference_backend(monkeypatch):
    monkeypatch.setenv("NDPACK_BACKEND", "numpy")
    monkeypatch.setenv("NDPACK_ON_INVALID", "raise")
