#!/usr/bin/env bash
# One seed of the 4.5 m crop at 2,000 steps on the scaling study's 250 scenes (plan.md).
#   experiments/crop-2026-12-07/run.sh OUT DATA SEED      (from the repository root)
# ASSIST3D (default assist3d), DEV, EXTRA as in experiments/scaling-2026-12-05/run.sh. Resumable (same command).
set -euo pipefail
OUT=${1:?usage: run.sh OUT DATA SEED}; DATA=${2:?}; SEED=${3:?}
A=${ASSIST3D:-assist3d}
DEV=${DEV:-../shared/data/real/dev}
EXTRA=${EXTRA:-../shared/data/real/scannet_scene0451_01.npy}
mkdir -p "$OUT"
$A probe --train "assist3d:$DATA" --max-train-scenes 250 --config experiments/crop-2026-12-07/crop45.yaml \
  --eval "array:$DEV" --eval "array:$EXTRA" --steps 2000 --seeds 1 --first-seed "$SEED" --hybrid --threads 2 \
  --device "${DEVICE:-cpu}" --out "$OUT/probe-crop45-s250-t2000" --json > "$OUT/probe-crop45-seed$SEED.json" \
  2> "$OUT/probe-crop45-seed$SEED.log"
