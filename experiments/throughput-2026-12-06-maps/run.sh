#!/usr/bin/env bash
# The float32 path's kernel maps from the dense-grid neighbour table (b71e07c) against the sorted-key search
# (609a2e9, the code before it), and the issue's baseline (the float32 path of 8af6226), on the same machine.
# bench-train --precision float32 on 8 household-sparse scenes, 20 steps after 3, runs alternated.
#   experiments/throughput-2026-12-06-maps/run.sh OUT      (from the repository root; [train] extra and git)
set -euo pipefail
OUT=${1:?usage: run.sh OUT}
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT"
for c in 8af6226 609a2e9 b71e07c; do
  [ -d "$OUT/$c" ] || git worktree add -f --detach "$OUT/$c" "$c"
done
[ -f "$OUT/hs8/manifest.json" ] || PYTHONPATH=src $PY -m assist3d generate --out "$OUT/hs8" --num-scenes 8 --seed 0 \
  --preset assist3d --config configs/household-sparse.yaml --rays full --workers 2 > "$OUT/generate.log" 2>&1
bench() {  # bench NAME COMMIT
  [ -s "$OUT/$1.json" ] && return 0  # a finished run is not repeated
  PYTHONPATH=$OUT/$2/src $PY -m assist3d bench-train --data "assist3d:$OUT/hs8" --steps 20 --precision float32 \
    --json > "$OUT/$1.tmp" && mv "$OUT/$1.tmp" "$OUT/$1.json"
}
for k in 0 1 2; do bench "search-$k" 609a2e9; bench "table-$k" b71e07c; done
for k in 0 1; do bench "base-$k" 8af6226; bench "table-b$k" b71e07c; done
for f in "$OUT"/*.json; do
  printf '%s\t%s\n' "$(basename "$f" .json)" "$(grep -o '"step_s_median": [0-9.]*' "$f" | awk '{print $2}')"
done
