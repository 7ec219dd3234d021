#!/usr/bin/env bash
# Prepare, on the 2-core VM, what run.sh needs on a lent GPU machine (which has torch but not assist3d's other
# dependencies, the asset library or a network):
#   .whl/                  pydantic & co. as wheels (pip download from the package registry)
#   .devdata/hs8.npz.xz    the 8 household-sparse scenes of docs/throughput.md, packed (scripts/pack_scenes.py)
# and the CPU reference on this VM (bench-train, today's default, 20 steps after 3), the figure the GPU is held to.
#   experiments/gpu-throughput/prepare.sh OUT     (from the repository root; [train] extra; OUT: scratch folder)
set -euo pipefail
OUT=${1:?usage: prepare.sh OUT}
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT" .whl .devdata
grep -qx '/.whl/' .git/info/exclude 2>/dev/null || printf '/.whl/\n/.devdata/\n' >> .git/info/exclude
[ -f "$OUT/hs8/manifest.json" ] || $PY -m assist3d generate --out "$OUT/hs8" --num-scenes 8 --seed 0 \
  --preset assist3d --config configs/household-sparse.yaml --rays full --workers 2 > "$OUT/generate.log" 2>&1
[ -f .devdata/hs8.npz.xz ] || $PY scripts/pack_scenes.py pack .devdata/hs8.npz.xz "assist3d:$OUT/hs8"
# the GPU image has Python 3.12 with numpy, scipy, pyyaml, typer and rich (the device tool's KINDS.md), not pydantic
compgen -G ".whl/pydantic-*.whl" > /dev/null || $PY -m pip download -q -d .whl --only-binary=:all: \
  --python-version 3.12 --implementation cp --platform manylinux2014_x86_64 pydantic
# the CPU reference, on the packed scenes the GPU will read (unpacked here the same way)
[ -d "$OUT/hs8-array" ] || $PY scripts/pack_scenes.py unpack .devdata/hs8.npz.xz "$OUT/hs8-array"
[ -s "$OUT/cpu-vm.json" ] || $PY -m assist3d bench-train --data "array:$OUT/hs8-array" --steps 20 --json \
  > "$OUT/cpu-vm.tmp" && mv "$OUT/cpu-vm.tmp" "$OUT/cpu-vm.json"
grep -o '"step_s_median": [0-9.]*\|"precision": "[a-z0-9]*"' "$OUT/cpu-vm.json" | head -2
du -sh .whl .devdata
