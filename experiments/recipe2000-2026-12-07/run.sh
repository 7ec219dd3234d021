#!/usr/bin/env bash
# real + 0.5 x ASSIST-3D at 2,000 steps, two folds (plan.md). Resumable: re-run the same command to continue.
#   experiments/recipe2000-2026-12-07/run.sh OUT          (from the repository root)
# ASSIST3D (the command), DEV (the dev scans), EXTRA (scene0451_01), DEVICE (cpu), DATA (250 ASSIST-3D scenes; default
# OUT/data, generated when missing), SEED (0).
set -euo pipefail
OUT=${1:?usage: run.sh OUT}
A=${ASSIST3D:-assist3d}
DEV=${DEV:-../shared/data/real/dev}
EXTRA=${EXTRA:-../shared/data/real/scannet_scene0451_01.npy}
DEVICE=${DEVICE:-cpu}
SEED=${SEED:-0}
mkdir -p "$OUT"
D=${DATA:-$OUT/data}
if [ -z "${DATA:-}" ]; then
  $A generate --out "$D" --num-scenes 250 --seed 0 --preset assist3d --workers 2 --rays full --json \
    > "$OUT/generate-250.json" 2> "$OUT/generate-250.log"
fi
fold() {  # fold NAME ROOM...: hold out the rooms given, train on the other dev scans
  local name=$1; shift
  local args=() f r held
  for f in "$DEV"/*.npy; do
    r=$(basename "$f" | cut -c1-9); held=0
    for h in "$@"; do [[ $r == "$h" ]] && held=1; done
    if (( held )); then args+=(--eval "array:$f"); else args+=(--train "array:$f" --weight 1); fi
  done
  args+=(--eval "array:$EXTRA" --train "assist3d:$D" --weight 0.5)
  date -u; echo "fold $name seed $SEED"
  $A probe "${args[@]}" --max-train-scenes 250 --steps 2000 --seeds 1 --first-seed "$SEED" --hybrid --threads 2 \
    --device "$DEVICE" --out "$OUT/mix-$name" --json > "$OUT/mix-$name-seed$SEED.json" 2> "$OUT/mix-$name-seed$SEED.log"
}
fold A scene0006 scene0007 scene0008
fold B scene0009 scene0010
date -u; echo DONE
