# Sourced by the bench/gpu_issue*.sh scripts: the output folder ($OUT), unbuffered Python, and the
# machine and versions written to $OUT/gpu.txt (and shown).
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$OUT/gpu.txt"
echo "cores: $(nproc)" | tee -a "$OUT/gpu.txt"
python3 -c "import numba, numba_cuda, warp, numpy; print('numba', numba.__version__, 'numba-cuda', numba_cuda.__version__, 'warp', warp.__version__, 'numpy', numpy.__version__)" 2>&1 | grep -v "^Warp" | tee -a "$OUT/gpu.txt"
# The card, for file names: h100 or h200.
CARD=$(nvidia-smi --query-gpu=name --format=csv,noheader | head -1 | grep -o 'H[0-9][0-9]*' | head -1 | tr H h)

# cold_first_packing FILE: a fresh machine's first packing of /tmp/armadillo.obj on Warp, and the next,
# with ndpack's, Warp's and the driver's caches off; the notices and the times go to FILE, and each
# module's compile time to /tmp/ndpack-cold-cache/compile-times.json.
cold_first_packing() {
  (export NDPACK_CACHE=/tmp/ndpack-cold-cache WARP_CACHE_PATH=/tmp/ndpack-cold-cache/warp CUDA_CACHE_DISABLE=1
   rm -rf /tmp/ndpack-cold-cache
   python3 - <<'PY' 2>&1 | grep -v "^Warp\|^Module" | tee "$1"
import time
import ndpack as nd
shape = nd.TriangleMesh.load("/tmp/armadillo.obj")
started = time.perf_counter()
nd.pack(shape, 3, backend="warp", mode="fast", progress=False)
first = time.perf_counter() - started
started = time.perf_counter()
nd.pack(shape, 3, backend="warp", mode="fast", progress=False)
print(f"warp, cuda: first packing of a mesh, cache empty: {first:.1f} s; the next: {time.perf_counter() - started:.2f} s")
PY
  )
}

# kernels VERSION NAME ARGS...: bench/profile_kernels.py with VERSION's ndpack (now: this checkout; base:
# .gpu2/base), unprofiled runs only, stages timed, the table to $OUT/NAME_VERSION.json.
kernels() {
  local version=$1 name=$2
  shift 2
  local path=$PYTHONPATH
  [ "$version" = base ] && path=$PWD/.gpu2/base:$PYTHONPATH
  PYTHONPATH=$path timeout 300 python3 bench/profile_kernels.py --stages --no-profiled \
    --out "$OUT/${name}_${version}.json" "$@" 2>&1 | grep -v "^Warp\|^Module"
}

# in_turns NAME CASE ARGS...: kernels of .gpu2/base and of this checkout in two turns (NAME_turnN_VERSION.json),
# each saving its spheres to /tmp/CASE_VERSION.npz for same_spheres; the stages' lines shown.
in_turns() {
  local name=$1 case=$2
  shift 2
  for turn in 1 2; do
    for version in base now; do
      kernels "$version" "${name}_turn${turn}" "$@" --spheres "/tmp/${case}_${version}.npz" | grep -E "^== |now: "
    done
  done
}

# same_spheres FILE CASE...: each case's spheres of .gpu2/base and of this checkout (/tmp/CASE_base.npz and
# /tmp/CASE_now.npz, written by kernels --spheres) side by side, to FILE and the screen: their counts, the
# largest change of a radius and of a centre, and their volumes (sums of radius^3).
same_spheres() {
  local file=$1
  shift
  python3 - "$@" <<'PY' | tee "$file"
import sys
import numpy as np
for case in sys.argv[1:]:
    base, now = (np.load(f"/tmp/{case}_{v}.npz") for v in ("base", "now"))
    same = len(base["radii"]) == len(now["radii"])
    change = float(np.abs(base["radii"] - now["radii"]).max()) if same else None
    moved = float(np.abs(base["centers"] - now["centers"]).max()) if same else None
    print(f"{case}, base against now: spheres {len(base['radii'])} and {len(now['radii'])}, largest radius change "
          f"{change}, largest centre change {moved}; volume {np.sum(base['radii'] ** 3):.6g} and "
          f"{np.sum(now['radii'] ** 3):.6g}")
PY
}

# issue48_inputs: the armadillo at /tmp/armadillo.obj and the kernel cache that issue 48's GPU scripts share.
issue48_inputs() {
  [ -f /tmp/armadillo.obj ] || xz -dc .gpu2/armadillo.obj.xz > /tmp/armadillo.obj
  export NDPACK_CACHE=/tmp/ndpack-gpu-cache WARP_CACHE_PATH=/tmp/ndpack-gpu-cache/warp
}

# need_base MODE: stop unless .gpu2/base holds the checkout to compare with (git archive BASE ndpack | tar x -C .gpu2/base).
need_base() {
  [ -d .gpu2/base/ndpack ] || { echo "$1: .gpu2/base/ndpack is missing" >&2; exit 2; }
}

# gather_in NAME: the results gather in /tmp/NAME (with gpu.txt), to be archived into $FINAL, the folder that
# comes back (many files would not all come back).
gather_in() {
  FINAL=$OUT
  OUT=/tmp/$1 && mkdir -p "$OUT" && cp "$FINAL/gpu.txt" "$OUT/"
}

# turns NAME PASSES: the armadillo at 100,000 with .gpu2/base's ndpack and this checkout's in turn, PASSES times
# (5 runs each), to $OUT/NAME_passK_{base,now}.json: a difference smaller than one lease's drift.
turns() {
  local name=$1 pass version
  for pass in $(seq 1 "$2"); do
    for version in base now; do
      kernels $version "${name}_pass${pass}" --backends warp --mesh /tmp/armadillo.obj --count 100000 --repeats 5
    done
  done
}

# fresh_runs NAME SECONDS BACKENDS...: a fresh machine's first packing of /tmp/armadillo.obj (bench/fresh_machine.py)
# on BACKENDS with this checkout and with .gpu2/base, each within SECONDS, to $OUT/NAME_now.json and $OUT/NAME_base.json.
fresh_runs() {
  local name=$1 seconds=$2 version path
  shift 2
  for version in now base; do
    path=$PYTHONPATH
    [ "$version" = base ] && path=$PWD/.gpu2/base:$PYTHONPATH
    PYTHONPATH=$path timeout "$seconds" python3 bench/fresh_machine.py --mesh /tmp/armadillo.obj --backends "$@" \
      --out "$OUT/${name}_${version}.json" 2>&1 | grep -v "^Warp\|^Module"
  done
}

# beside_and_store_tests NAME: the armadillo at 100,000 on numba-cuda, Warp and numba on the host's cores in one
# process ($OUT/NAME_now.json), then the device store's tests on this GPU ($OUT/gpu_tests_${CARD}_issue48_${STEP}.txt).
beside_and_store_tests() {
  kernels now "$1" --backends numba-cuda warp numba --mesh /tmp/armadillo.obj --count 100000 --repeats 3 \
    | grep -E "^== |now: "
  timeout 150 python3 -m pytest -q -p no:cacheprovider tests/backends/test_backends.py -k "small_device or fast_mode" \
    2>&1 | tail -4 | tee "$OUT/gpu_tests_${CARD}_issue48_${STEP}.txt"
}
