#!/usr/bin/env bash
# bfloat16 against float32 training on the real dev scans (plan.md). Resumable: re-run to finish.
#   experiments/precision-2026-12-05/run.sh OUT        (from the repository root)
set -euo pipefail
OUT=${1:?usage: run.sh OUT}
HERE=$(cd "$(dirname "$0")" && pwd)
DEV=${DEV:-../shared/data/real/dev}
EXTRA=${EXTRA:-../shared/data/real/scannet_scene0451_01.npy}
A=${ASSIST3D:-assist3d}
PY=${PYTHON:-python}
mkdir -p "$OUT"
$A generate --out "$OUT/data" --num-scenes 60 --seed 0 --preset assist3d --config configs/household-sparse.yaml --workers 2
for seed in 0 1; do
  for arm in float32 bfloat16; do
    $A probe --train "assist3d:$OUT/data" --eval "array:$DEV" --steps 200 --seeds 1 --first-seed "$seed" --threads 2 \
      --config "$HERE/$arm.yaml" --out "$OUT/$arm" --json > "$OUT/$arm-seed$seed.json"
  done
done
for arm in float32 bfloat16; do
  $PY scripts/hybrid_eval.py "$OUT/$arm/seed_0/model.pt" "$OUT/$arm/seed_1/model.pt" --eval "array:$DEV" --eval "array:$EXTRA" \
    --out "$OUT/hybrid-$arm.json"
done
