#!/usr/bin/env bash
# The documented CPU run (docs/model.md): train the small-cpu preset on a few scenes until it fits
# them (AP50 on the training scenes), then run predict + evaluate with the same checkpoint on the
# real ScanNet scan.
#
#   scripts/fit_small.sh [WORK_DIR]
#
# Environment:
#   FIT_SOURCE=generate|toy   generate (default): `assist3d generate --num-scenes 4 --config
#                             configs/generate-sparse.yaml` (sparsely furnished generated rooms);
#                             toy: 4 box-room scenes from assist3d.learn.engine.toy (Pointcept layout).
#   GEN_CONFIG=FILE           generation config for FIT_SOURCE=generate (default
#                             configs/generate-sparse.yaml; the paper's density gives 150-250
#                             instances per room, too many for a 2-core memorisation run).
#   FIT_CONFIG=FILE           training config (default: configs/small-cpu.yaml).
#   FIT_EPOCHS=N              override the preset's epochs.
#   REAL_SCAN=PATH            the real scan (default ../shared/data/real/scannet_scene0451_01.npy).
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
WORK="${1:-${TMPDIR:-/tmp}/assist3d_fit_small}"
PY="${PYTHON:-$ROOT/.venv/bin/python}"
A3D="$PY -m assist3d"
SOURCE="${FIT_SOURCE:-generate}"
REAL_SCAN="${REAL_SCAN:-$ROOT/../shared/data/real/scannet_scene0451_01.npy}"
EPOCH_ARGS=()
if [[ -n "${FIT_EPOCHS:-}" ]]; then EPOCH_ARGS=(--epochs "$FIT_EPOCHS"); fi

mkdir -p "$WORK"
start=$(date +%s)

case "$SOURCE" in
  toy)
    "$PY" -c "from assist3d.learn.engine.toy import write_toy_dataset; \
write_toy_dataset('$WORK/scenes', 4, seed=1, num_objects=6, room_m=4.0, density_per_m2=1000)"
    SPEC="synthetic=pointcept:$WORK/scenes"
    GT="pointcept:$WORK/scenes"
    CONFIG="${FIT_CONFIG:-$ROOT/configs/small-cpu.yaml}"
    ;;
  generate)
    $A3D generate --out "$WORK/scenes" --num-scenes 4 --config "${GEN_CONFIG:-$ROOT/configs/generate-sparse.yaml}"
    SPEC="synthetic=assist3d:$WORK/scenes"
    GT="assist3d:$WORK/scenes"
    CONFIG="${FIT_CONFIG:-$ROOT/configs/small-cpu.yaml}"
    ;;
  *) echo "FIT_SOURCE must be toy or generate, got $SOURCE" >&2; exit 2 ;;
esac

$A3D train --config "$CONFIG" --data "$SPEC" --out "$WORK/train" ${EPOCH_ARGS[@]+"${EPOCH_ARGS[@]}"}
CKPT="$WORK/train/last.pt"
trained=$(date +%s)

$A3D predict --checkpoint "$CKPT" --data "$GT" --out "$WORK/pred_train" --device cpu
$A3D evaluate --gt "$GT" --pred "$WORK/pred_train" --json | tee "$WORK/eval_train.json"

if [[ -f "$REAL_SCAN" ]]; then
  $A3D predict --checkpoint "$CKPT" --data "array:$REAL_SCAN" --out "$WORK/pred_real" --device cpu
  $A3D evaluate --gt "array:$REAL_SCAN" --pred "$WORK/pred_real" --json | tee "$WORK/eval_real.json"
else
  echo "real scan not found at $REAL_SCAN: skipping the real-scan evaluation" >&2
fi
end=$(date +%s)
echo "{\"train_seconds\": $((trained - start)), \"total_seconds\": $((end - start))}" | tee "$WORK/timing.json"
