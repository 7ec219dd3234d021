#!/usr/bin/env bash
# Generate one dataset per generator preset (ASSIST-3D, RandomRooms-style, Holodeck-style,
# ASSIST-3D without context) with the same seed, assets and render settings, then compare them
# with `assist3d metrics` (JSON table + PNG plot). Resumable: an existing dataset folder is
# completed, not regenerated.
#
#   scripts/compare_generators.sh [OUT_DIR] [NUM_SCENES] [VIEWS_PER_POINT]
#
# Defaults: OUT_DIR=compare_out, NUM_SCENES=50, VIEWS_PER_POINT=12 (the paper's). Set WORKERS
# (default 2), SEED (default 0), PRESETS (default "assist3d randomrooms holodeck-style no-context")
# ASSETS (an asset catalog folder; default: the built-in procedural library) and ASSIST3D
# (default: the assist3d on PATH, else .venv/bin/assist3d) in the environment.
set -euo pipefail

OUT=${1:-compare_out}
N=${2:-50}
VIEWS=${3:-12}
WORKERS=${WORKERS:-2}
SEED=${SEED:-0}
PRESETS=${PRESETS:-"assist3d randomrooms holodeck-style no-context"}
ASSET_ARGS=()
if [[ -n "${ASSETS:-}" ]]; then ASSET_ARGS=(--assets "$ASSETS"); fi
if [[ -z "${ASSIST3D:-}" ]]; then
  if command -v assist3d >/dev/null 2>&1; then ASSIST3D=assist3d; else ASSIST3D="$(dirname "$0")/../.venv/bin/assist3d"; fi
fi

mkdir -p "$OUT"
CFG="$OUT/render.yaml"
printf 'render:\n  views_per_point: %d\n' "$VIEWS" > "$CFG"

DATASETS=()
for p in $PRESETS; do
  start=$(date +%s)
  "$ASSIST3D" generate --out "$OUT/$p" --num-scenes "$N" --seed "$SEED" --preset "$p" --config "$CFG" \
    --workers "$WORKERS" "${ASSET_ARGS[@]}" --json > "$OUT/$p.generate.json"
  echo "generated $p: $N scenes in $(( $(date +%s) - start )) s" >&2
  DATASETS+=("$OUT/$p")
done

start=$(date +%s)
"$ASSIST3D" metrics "${DATASETS[@]}" --json --plot "$OUT/metrics.png" --save-codebook "$OUT/codebook.npz" \
  > "$OUT/metrics.json"
echo "metrics: $(( $(date +%s) - start )) s -> $OUT/metrics.json, $OUT/metrics.png" >&2
cat "$OUT/metrics.json"
