#!/usr/bin/env bash
# plan.md: doors and windows as objects at 2,000 steps on 250 scenes, seeds 0 and 1 (resumable: re-run it).
#   experiments/openings2000/run.sh OUT      (from the repository root)
set -euo pipefail
OUT=${1:?usage: run.sh OUT}
A=${ASSIST3D:-assist3d}
mkdir -p "$OUT"
$A generate --out "$OUT/data" --num-scenes 250 --seed 0 --preset assist3d --rays full --workers 2 \
  --config experiments/fill-2026-11-26/fill.yaml --json > "$OUT/generate-250.json" 2> "$OUT/generate-250.log"
ASSIST3D="$A" DATA="$OUT/data" SEEDS="${SEEDS:-0 1}" experiments/scaling-2026-12-05/run.sh "$OUT" "2000:250"
