#!/usr/bin/env bash
# Training throughput of the closed-form shape features (b24776d) against the code before them (8af6226):
# bench-train on 8 household-sparse scenes, 20 steps, the two trees' runs alternated in one session.
#   experiments/throughput-2026-12-06/run.sh OUT      (from the repository root; needs the [train] extra and git)
set -euo pipefail
OUT=${1:?usage: run.sh OUT}
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT"
[ -d "$OUT/old" ] || git worktree add -f --detach "$OUT/old" 8af6226
PYTHONPATH=src $PY -m assist3d generate --out "$OUT/hs8" --num-scenes 8 --seed 0 --preset assist3d \
  --config configs/household-sparse.yaml --rays full --workers 2 > "$OUT/generate.log" 2>&1
bench() {  # bench NAME SRC ARGS...
  local name=$1 src=$2; shift 2
  PYTHONPATH=$src $PY -m assist3d bench-train --data "assist3d:$OUT/hs8" --steps 20 --json "$@" > "$OUT/$name.json"
}
for k in 0 1 2; do bench "old-$k" "$OUT/old/src"; bench "new-$k" src; done
for k in 0 1; do bench "oldf32-b$k" "$OUT/old/src" --precision float32; bench "new-b$k" src; done
grep -H step_s_median "$OUT"/*.json
