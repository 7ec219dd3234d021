#!/usr/bin/env bash
# Train a candidate for the shipped segmenter (experiments/fidelity-log.md, "The shipped model"): generated data
# only, the default recipe, seed 0, then score it with both inference paths on the real scans.
#
#   scripts/train_shipped.sh ASSETS OUT_DIR          # env: STEPS (1200), N0 (60), N1 (180),
#                                                    #      DEV (../shared/data/real/dev),
#                                                    #      EXTRA (../shared/data/real/scannet_scene0451_01.npy)
#                                                    #      PROBE_CONFIG (configs/segmenter-pre-ema.yaml, the
#                                                    #      recipe of the documented candidates; "" for today's
#                                                    #      defaults, with weight averaging)
#
# ASSETS is an asset library (docs/metrics.md: the 702-class Sweet Home 3D + procedural catalog).
# Two ASSIST-3D datasets are generated, N0 scenes with dataset seed 0 (the 60-scene set of the
# generator comparison) and N1 scenes with dataset seed 1, and the segmenter is trained on both for
# STEPS steps (resumable: re-running the script continues where it stopped). The model is not copied
# into the package: run `python scripts/ship_model.py OUT_DIR/probe/seed_0/model.pt` for that.
set -euo pipefail
ASSETS=${1:?usage: scripts/train_shipped.sh ASSETS OUT_DIR}
OUT=${2:?usage: scripts/train_shipped.sh ASSETS OUT_DIR}
STEPS=${STEPS:-1200}; N0=${N0:-60}; N1=${N1:-180}
DEV=${DEV:-../shared/data/real/dev}
EXTRA=${EXTRA:-../shared/data/real/scannet_scene0451_01.npy}
ASSIST3D=${ASSIST3D:-assist3d}
PYTHON=${PYTHON:-python}
HERE=$(cd "$(dirname "$0")" && pwd)
PROBE_CONFIG=${PROBE_CONFIG-$HERE/../configs/segmenter-pre-ema.yaml}
CONFIG_ARGS=()
if [[ -n "$PROBE_CONFIG" ]]; then CONFIG_ARGS=(--config "$PROBE_CONFIG"); fi
mkdir -p "$OUT"
# generate skips the scenes a folder already holds, so a re-run only finishes what is missing
$ASSIST3D generate --out "$OUT/data-s0" --num-scenes "$N0" --seed 0 --preset assist3d --workers 2 --rays full --assets "$ASSETS"
$ASSIST3D generate --out "$OUT/data-s1" --num-scenes "$N1" --seed 1 --preset assist3d --workers 2 --rays full --assets "$ASSETS"
$ASSIST3D probe --train "assist3d:$OUT/data-s0" --train "assist3d:$OUT/data-s1" --eval "array:$DEV" \
  --steps "$STEPS" --seeds 1 "${CONFIG_ARGS[@]}" --out "$OUT/probe" --json > "$OUT/probe.json"
$PYTHON "$HERE/hybrid_eval.py" "$OUT/probe/seed_0/model.pt" --eval "array:$DEV" --eval "array:$EXTRA" \
  --out "$OUT/hybrid.json"
