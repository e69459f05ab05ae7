# Sourced by the bench/gpu_issue*.sh scripts: the output folder ($OUT), unbuffered Python, and the
# machine and versions written to $OUT/gpu.txt (and shown).
OUT=${OUT:-/tmp/out}
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$OUT/gpu.txt"
echo "cores: $(nproc)" | tee -a "$OUT/gpu.txt"
python3 -c "import numba, numba_cuda, warp, numpy; print('numba', numba.__version__, 'numba-cuda', numba_cuda.__version__, 'warp', warp.__version__, 'numpy', numpy.__version__)" 2>&1 | grep -v "^Warp" | tee -a "$OUT/gpu.txt"
