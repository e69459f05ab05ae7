#!/usr/bin/env bash
# The GPU machine's part of issue 4 (meshes), after the two set-up runs (.gpu1, .gpu2):
#   source .gpu2/setup.sh && bash bench/gpu_meshes.sh [path to armadillo.obj]
# It installs the carried fcpw and libigl wheels (.gpu3/) if present, runs the mesh tests on
# both GPU backends, the query benchmark (bench/mesh_queries.py), and a 10,000-sphere packing of
# the armadillo per backend. Results go to $OUT.
set -uo pipefail
OUT=${OUT:-/tmp/out}
MESH=${1:-.gpu3/armadillo.obj}
mkdir -p "$OUT"
if ls .gpu3/*.whl >/dev/null 2>&1 && ! python3 -c "import igl, fcpw" 2>/dev/null; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/gpu-site .gpu3/*.whl
fi
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$OUT/gpu.txt"
timeout 400 python3 -m pytest -q -x -p no:cacheprovider tests/backends/test_backends.py -k mesh tests/shapes/test_mesh.py 2>&1 \
  | tail -15 | tee "$OUT/mesh_tests.txt"
NUMBA_NUM_THREADS=16 timeout 400 python3 bench/mesh_queries.py --mesh "$MESH" --out "$OUT/mesh_queries_gpu.json" 2>&1 \
  | grep -v "^Warp\|^Module" | tee "$OUT/mesh_queries.txt"
NUMBA_NUM_THREADS=16 timeout 300 python3 - "$MESH" <<'PY' 2>&1 | tee "$OUT/mesh_packing.txt"
import sys, time
import ndpack as nd
mesh = nd.TriangleMesh.load(sys.argv[1])
for name in ("warp", "numba-cuda", "numba"):
    started = time.perf_counter()
    packing = nd.pack(mesh, n=10_000, batch=64, seed=0, backend=name, time_budget=60, progress=False)
    elapsed = time.perf_counter() - started
    print(f"{name:10s} {len(packing.radii):6d} spheres  fill {packing.fill:.4f}  {elapsed:6.1f} s "
          f"(packing {packing.stats.time[-1]:.1f} s)  valid {packing.verify().ok}", flush=True)
PY
