#!/usr/bin/env bash
# Scaling curves (plan.md). Resumable: every probe keeps its finished seeds and resumes an unfinished one
# from its last.pt, and generate keeps the scenes a folder holds; re-run the same command to continue.
#   experiments/scaling-2026-12-05/run.sh OUT [POINTS]     (from the repository root)
# The data is the full render (--rays full), as when the study began (the ray budget became the default later).
# POINTS: space-separated "STEPS:SCENES" (default: the plan's order for a CPU); SEEDS (default "0 1").
# DATA: train on a dataset made elsewhere instead of generating OUT/data (2,000:2,000 used the 2,000 scenes
# of scripts/scale_bench.sh, the default ray-budget render; see plan.md).
# CONFIG: a segmenter config YAML for every probe (e.g. experiments/crop-2026-12-07/crop45.yaml; use its own OUT).
set -euo pipefail
OUT=${1:?usage: run.sh OUT [POINTS]}
POINTS=${2:-"200:250 821:250 2000:250 2000:60 8210:250"}
SEEDS=${SEEDS:-0 1}
A=${ASSIST3D:-assist3d}
DEV=${DEV:-../shared/data/real/dev}
EXTRA=${EXTRA:-../shared/data/real/scannet_scene0451_01.npy}
DEVICE=${DEVICE:-cpu}
CFG=()
[ -n "${CONFIG:-}" ] && CFG=(--config "$CONFIG")
mkdir -p "$OUT"
NEED=0
for p in $POINTS; do s=${p#*:}; [ "$s" -gt "$NEED" ] && NEED=$s; done
if [ -n "${DATA:-}" ]; then
  D=$DATA
else
  D=$OUT/data
  $A generate --out "$D" --num-scenes "$NEED" --seed 0 --preset assist3d --workers 2 --rays full --json \
    > "$OUT/generate-$NEED.json" 2> "$OUT/generate-$NEED.log"
fi
for p in $POINTS; do
  steps=${p%%:*}; scenes=${p#*:}
  for k in $SEEDS; do
    date -u; echo "probe steps $steps scenes $scenes seed $k"
    $A probe --train "assist3d:$D" --max-train-scenes "$scenes" --eval "array:$DEV" --eval "array:$EXTRA" \
      --steps "$steps" --seeds 1 --first-seed "$k" --hybrid --threads 2 --device "$DEVICE" "${CFG[@]}" \
      --out "$OUT/probe-s$scenes-t$steps" --json > "$OUT/probe-s$scenes-t$steps-seed$k.json" \
      2> "$OUT/probe-s$scenes-t$steps-seed$k.log"
  done
done
date -u; echo DONE
