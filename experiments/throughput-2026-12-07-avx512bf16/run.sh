#!/usr/bin/env bash
# Training throughput on a CPU with AVX-512 BF16 but no AMX (the AMD EPYC VMs of 2026-12-07): the issue's baseline
# (the float32 path of 8af6226) against today's code in float32 and in its default (`auto`, bfloat16 where the CPU
# multiplies it natively), on the same machine, runs alternated. bench-train on the 8 household-sparse scenes of
# docs/throughput.md, 20 steps after 3.
#   experiments/throughput-2026-12-07-avx512bf16/run.sh OUT [REV]   (from the repository root; [train] extra and git;
#   REV: the commit measured as today's code, default HEAD)
set -euo pipefail
OUT=${1:?usage: run.sh OUT [REV]}
REV=$(git rev-parse --short "${2:-HEAD}")
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT"
for c in 8af6226 "$REV"; do
  [ -d "$OUT/$c" ] || git worktree add -f --detach "$OUT/$c" "$c" > /dev/null
done
[ -f "$OUT/hs8/manifest.json" ] || PYTHONPATH=src $PY -m assist3d generate --out "$OUT/hs8" --num-scenes 8 --seed 0 \
  --preset assist3d --config configs/household-sparse.yaml --rays full --workers 2 > "$OUT/generate.log" 2>&1
bench() {  # bench NAME COMMIT PRECISION
  [ -s "$OUT/$1.json" ] && return 0  # a finished run is not repeated
  PYTHONPATH=$OUT/$2/src $PY -m assist3d bench-train --data "assist3d:$OUT/hs8" --steps 20 --precision "$3" \
    --json > "$OUT/$1.tmp" && mv "$OUT/$1.tmp" "$OUT/$1.json"
}
for k in 0 1 2; do
  bench "base-$k" 8af6226 float32; bench "f32-$k" "$REV" float32; bench "auto-$k" "$REV" auto
done
for f in "$OUT"/*.json; do
  printf '%s\t%s\t%s\n' "$(basename "$f" .json)" "$(grep -o '"step_s_median": [0-9.]*' "$f" | awk '{print $2}')" \
    "$(grep -o '"precision": "[a-z0-9]*"' "$f" | head -1)"
done
