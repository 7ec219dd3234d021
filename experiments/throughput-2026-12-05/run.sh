#!/usr/bin/env bash
# The training-throughput figures of docs/throughput.md: bench-train on 8 household-sparse scenes, the
# float32 and the bfloat16 path alternated, one warm-up pair and three counted pairs, each run's JSON kept.
#   experiments/throughput-2026-12-05/run.sh OUT      (from the repository root; needs the [train] extra)
set -euo pipefail
OUT=${1:?usage: run.sh OUT}
A=${ASSIST3D:-assist3d}
mkdir -p "$OUT"
$A generate --out "$OUT/hs8" --num-scenes 8 --seed 0 --preset assist3d --config configs/household-sparse.yaml --workers 2 \
  > "$OUT/generate.log" 2>&1
for k in 0 1 2 3; do   # k = 0 is the warm-up pair
  for p in bfloat16 float32; do
    /usr/bin/time -v $A bench-train --data "assist3d:$OUT/hs8" --steps 20 --precision "$p" --json \
      > "$OUT/$p-$k.json" 2> "$OUT/$p-$k.time"
  done
done
grep -H step_s_median "$OUT"/*.json
