"""Importing ndpack stays light: no GPU framework, no plotting, no Dask (only pack_many(client=...) needs it)."""

import subprocess
import sys


def test_import_pulls_in_no_heavy_framework():
    code = (
        "import sys, ndpack; "
        "heavy = [m for m in ('warp', 'numba', 'numba.cuda', 'numba_cuda', 'matplotlib', 'trimesh', 'manifold3d', "
        "'dask', 'distributed') "
        "if m in sys.modules]; "
        "print(','.join(heavy))"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == ""
