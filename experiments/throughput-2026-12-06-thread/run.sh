#!/usr/bin/env bash
# Training throughput with the examples built in a background thread (--loader-thread) against the same code
# building them in the step (--no-loader-thread), and the issue's baseline (the float32 path of 8af6226).
# The thread was not adopted and left the package: both arms run the tree of f9c443b, which had the flag.
# bench-train on 8 household-sparse scenes, 20 steps after 3, the runs alternated in one session.
#   experiments/throughput-2026-12-06-thread/run.sh OUT      (from the repository root; [train] extra and git)
set -euo pipefail
OUT=${1:?usage: run.sh OUT}
PY=${PYTHON:-.venv/bin/python}
mkdir -p "$OUT"
[ -d "$OUT/old" ] || git worktree add -f --detach "$OUT/old" 8af6226
[ -d "$OUT/thr" ] || git worktree add -f --detach "$OUT/thr" f9c443b
[ -f "$OUT/hs8/manifest.json" ] || PYTHONPATH=src $PY -m assist3d generate --out "$OUT/hs8" --num-scenes 8 --seed 0 \
  --preset assist3d --config configs/household-sparse.yaml --rays full --workers 2 > "$OUT/generate.log" 2>&1
bench() {  # bench NAME SRC ARGS...
  local name=$1 src=$2; shift 2
  PYTHONPATH=$src $PY -m assist3d bench-train --data "assist3d:$OUT/hs8" --steps 20 --json "$@" \
    > "$OUT/$name.json"
}
for k in 0 1 2; do bench "nothread-$k" "$OUT/thr/src" --no-loader-thread; bench "thread-$k" "$OUT/thr/src" --loader-thread; done
for k in 0 1; do bench "oldf32-$k" "$OUT/old/src" --precision float32; bench "thread-b$k" "$OUT/thr/src" --loader-thread; done
for f in "$OUT"/*.json; do
  printf '%s\t%s\n' "$(basename "$f" .json)" "$(grep -o '"step_s_median": [0-9.]*' "$f" | awk '{print $2}')"
done
