#!/usr/bin/env bash
# bench-train before (OLD, a checkout of 679013d) and after (this tree), alternated, three pairs.
#   experiments/throughput-2026-12-07-copies/run.sh OUT DATA OLD   (from the repository root)
set -euo pipefail
OUT=${1:?usage: run.sh OUT DATA OLD}; DATA=${2:?}; OLD=${3:?}
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT"
for k in 0 1 2; do
  PYTHONPATH=$OLD/src $PY -m assist3d bench-train --data "assist3d:$DATA" --steps 20 --json > "$OUT/old-$k.json" 2>/dev/null
  PYTHONPATH=src $PY -m assist3d bench-train --data "assist3d:$DATA" --steps 20 --json > "$OUT/new-$k.json" 2>/dev/null
done
grep -H step_s_median "$OUT"/*.json
