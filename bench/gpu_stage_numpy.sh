#!/usr/bin/env bash
# After ../shared/device/stage.sh: carry numpy 2.4 to the GPU machine in run 1 (.gpu1), where there is
# room, so that numba-cuda's CUDA target works there (the image's numpy 2.5 breaks it: np.row_stack is
# gone). Its wheel (17 MB) would take .gpu2 past a run's 64 MiB; recompressed without its tests it is
# 9 MB. Run from the project's root:   bash bench/gpu_stage_numpy.sh
# Then run 1 copies it to the machine's stage and run 2's setup unpacks it into /tmp/gpu-site, ahead of
# the image's numpy (every run then uses numpy 2.4: name it with the figures).
set -euo pipefail
VERSION=${NUMPY_VERSION:-2.4.6}
[ -f .gpu1/receive.sh ] && [ -f .gpu2/setup.sh ] || { echo "run ../shared/device/stage.sh first" >&2; exit 2; }
work=$(mktemp -d)
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
  --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64 \
  -d "$work/wheel" "numpy==$VERSION"
mkdir -p "$work/site" && (cd "$work/site" && python3 -m zipfile -e "$work"/wheel/numpy-*.whl . \
  && rm -rf numpy/tests numpy/*/tests && tar cf - . | xz -T0 -9 > "$OLDPWD/.gpu1/numpy-$VERSION.tar.xz")
rm -rf "$work"
grep -q "gpu-stage/numpy" .gpu1/receive.sh || cat >> .gpu1/receive.sh <<'EOS'
mkdir -p /tmp/gpu-stage/numpy && cp .gpu1/numpy-*.tar.xz /tmp/gpu-stage/numpy/
EOS
grep -q "gpu-stage/numpy" .gpu2/setup.sh || python3 - <<'EOS'
from pathlib import Path
setup = Path(".gpu2/setup.sh")
text = setup.read_text()
unpack = ("# numpy 2.4 (the image's 2.5 breaks numba-cuda's CUDA target), where run 1 brought it.\n"
          "if [ ! -f /tmp/gpu-site/numpy/__init__.py ] && ls /tmp/gpu-stage/numpy/numpy-*.tar.xz >/dev/null 2>&1; then\n"
          "  xz -dc /tmp/gpu-stage/numpy/numpy-*.tar.xz | tar x -C /tmp/gpu-site\n"
          "fi\n")
setup.write_text(text.replace("export PYTHONPATH=", unpack + "export PYTHONPATH=", 1))
EOS
echo "staged: .gpu1 $(du -sh .gpu1 | cut -f1) (numpy $VERSION added), .gpu2 $(du -sh .gpu2 | cut -f1)"
