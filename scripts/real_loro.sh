#!/usr/bin/env bash
# The real-only rows of experiments/fidelity-log.md: the segmenter trained on real scans, leave one room out
# (rescans of a room share the first 9 characters of their name: all of a room's scans are held out
# together), the same budget and recipe as the generator comparison.
#
#   scripts/real_loro.sh DEV_DIR OUT_DIR            # env: STEPS (200), SEEDS (3), PAR (folds at once, 1),
#                                                   #      PROBE_ARGS (extra probe flags, e.g. "--device cuda")
#                                                   #      PROBE_CONFIG (configs/segmenter-pre-ema.yaml, the
#                                                   #      published rows' recipe; "" for today's defaults)
set -euo pipefail
DEV=${1:?usage: scripts/real_loro.sh DEV_DIR OUT_DIR}
OUT=${2:?usage: scripts/real_loro.sh DEV_DIR OUT_DIR}
STEPS=${STEPS:-200}; SEEDS=${SEEDS:-3}; PAR=${PAR:-1}
ASSIST3D=${ASSIST3D:-assist3d}
PROBE_CONFIG=${PROBE_CONFIG-$(cd "$(dirname "$0")/.." && pwd)/configs/segmenter-pre-ema.yaml}
CONFIG_ARGS=()
if [[ -n "$PROBE_CONFIG" ]]; then CONFIG_ARGS=(--config "$PROBE_CONFIG"); fi
mkdir -p "$OUT"
rooms=$(ls "$DEV"/*.npy | xargs -n1 basename | cut -c1-9 | sort -u)
fold() {
  local r=$1 train_args=() eval_args=()
  for f in "$DEV"/*.npy; do
    if [[ "$(basename "$f" | cut -c1-9)" == "$r" ]]; then eval_args+=(--eval "array:$f"); else train_args+=(--train "array:$f"); fi
  done
  # shellcheck disable=SC2086
  $ASSIST3D probe "${train_args[@]}" "${eval_args[@]}" --steps "$STEPS" --seeds "$SEEDS" ${PROBE_ARGS:-} \
    "${CONFIG_ARGS[@]}" --out "$OUT/$r" --json > "$OUT/$r.json" 2> "$OUT/$r.log"
  echo "fold $r done" >&2
}
n=0
for r in $rooms; do
  fold "$r" &
  n=$((n + 1))
  if (( n % PAR == 0 )); then wait; fi
done
wait
