"""Shared by the tests of the cooperative walks (Warp's and numba-cuda's)."""

import numpy as np


def check_against_serial(launch, count, serial=False):
    """Run a test kernel three times and check the cooperative walk against the serial one.

    ``launch(limits)`` runs the kernel on ``count`` points under ``limits`` (count,) and returns
    (count, 4): the cooperative walk's element, the serial walk's, and their squared distances (-1
    where none). The runs: no limit; the serial distance itself, widened (a converge step's); half of
    it, where nothing is nearer. Ties may pick another element at the same distance, unless ``serial``
    (the cooperative walk fell back to the serial one)."""
    limits = np.full(count, 1e30)
    out = None
    for run in range(3):
        if run == 1:
            limits = out[:, 3] * 1.000001 + 1e-30
        elif run == 2:
            limits = out[:, 3] * 0.5
        out = launch(limits)
        if run < 2:
            assert (out[:, 1] >= 0).all()
        else:
            assert (out[:, 0] == -1).all() and (out[:, 1] == -1).all()
        np.testing.assert_array_equal(out[:, 2], out[:, 3])  # the same distance
        if serial:
            np.testing.assert_array_equal(out[:, 0], out[:, 1])
