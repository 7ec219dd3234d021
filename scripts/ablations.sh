#!/usr/bin/env bash
# Datasets for the paper's ablation tables, each generated through `assist3d generate --preset`
# and compared with `assist3d metrics` (JSON table + PNG plot per table).
#
#   scripts/ablations.sh TABLE [OUT_DIR] [NUM_SCENES]
#
# TABLE is one of
#   pairing   co-occurrence pairing q = 1.0 / 0.66 / 0.33 / 0 (context complexity ablation)
#   clusters  shape clusters k = 1..5 (geometry diversity ablation; runs `assist3d cluster-assets
#             --k 5` on a copy of the catalog first, so the shared catalog is left as it was)
#   points    rendered RGB-D fusion vs points sampled on the meshes
#   classes   class count 100 / 200 / 400 (needs a catalog with that many classes, e.g. Sweet Home 3D)
#   scenes    scene count: NUM_SCENES scenes of the paper's preset; train on prefixes of it
# Environment: WORKERS (default 2), SEED (default 0), ASSETS (catalog folder; default: the
# built-in procedural library), CONFIG (an extra YAML config applied to every dataset, e.g. to
# lower render.views_per_point or the object counts), ASSIST3D (the CLI to run), PYTHON (the
# interpreter assist3d is installed in; used to find the default catalog).
set -euo pipefail

TABLE=${1:?usage: scripts/ablations.sh pairing|clusters|points|classes|scenes [OUT_DIR] [NUM_SCENES]}
OUT=${2:-ablation_$TABLE}
N=${3:-50}
WORKERS=${WORKERS:-2}
SEED=${SEED:-0}
if [[ -z "${ASSIST3D:-}" ]]; then
  if command -v assist3d >/dev/null 2>&1; then ASSIST3D=assist3d; else ASSIST3D="$(dirname "$0")/../.venv/bin/assist3d"; fi
fi
mkdir -p "$OUT"
ASSETS_DIR=${ASSETS:-}

case "$TABLE" in
  pairing) PRESETS="pairing-0 pairing-0.33 pairing-0.66 pairing-1.0" ;;
  clusters)
    PRESETS="clusters-1 clusters-2 clusters-3 clusters-4 clusters-5"
    if [[ -z "$ASSETS_DIR" ]]; then
      # the catalog `assist3d generate` would use (the built-in procedural library by default)
      ASSETS_DIR=$("${PYTHON:-$(dirname "$0")/../.venv/bin/python}" -c \
        'from assist3d.assets import open_catalog; print(open_catalog(None).root)')
    fi
    if [[ ! -d "$OUT/catalog" ]]; then
      cp -a "$ASSETS_DIR" "$OUT/catalog.tmp" && mv "$OUT/catalog.tmp" "$OUT/catalog"
    fi
    ASSETS_DIR="$OUT/catalog"
    "$ASSIST3D" cluster-assets --library "$ASSETS_DIR" --k 5 >&2 ;;
  points) PRESETS="assist3d mesh-sampled" ;;
  classes) PRESETS="classes-100 classes-200 classes-400" ;;
  scenes) PRESETS="assist3d" ;;
  *) echo "unknown table $TABLE (pairing, clusters, points, classes, scenes)" >&2; exit 2 ;;
esac

ARGS=(--num-scenes "$N" --seed "$SEED" --workers "$WORKERS")
if [[ -n "$ASSETS_DIR" ]]; then ARGS+=(--assets "$ASSETS_DIR"); fi
if [[ -n "${CONFIG:-}" ]]; then ARGS+=(--config "$CONFIG"); fi
DATASETS=()
for p in $PRESETS; do
  start=$(date +%s)
  "$ASSIST3D" generate --out "$OUT/$p" --preset "$p" "${ARGS[@]}" --json > "$OUT/$p.generate.json"
  echo "generated $p: $N scenes in $(( $(date +%s) - start )) s" >&2
  DATASETS+=("$OUT/$p")
done
# each dataset's manifest records the catalog it was generated from
"$ASSIST3D" metrics "${DATASETS[@]}" --json --plot "$OUT/metrics.png" > "$OUT/metrics.json"
cat "$OUT/metrics.json"
