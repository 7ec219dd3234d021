#!/usr/bin/env bash
# The paper's generator comparison on real scans, at small scale (experiments/fidelity-log.md):
# one dataset per generator (equal scene counts, same catalog, seed and render settings), the CPU
# segmenter trained on each for the same number of steps with K seeds, zero-shot AP on the real dev
# scans; plus the geometric reference and a real-only model (leave-one-room-out over the dev scans).
# Resumable at every level: re-running completes what is missing and recomputes nothing finished.
#
#   scripts/fidelity.sh OUT_DIR
#
# Environment: STEPS (training steps per run, default 600), SEEDS (default 3), SCENES (scenes per
# generator, default 60), GENERATORS (default "assist3d randomrooms holodeck-style no-context
# mesh-sampled"), ASSETS (catalog folder; the docs use Sweet Home 3D + the procedural library),
# DEV (real scans, default ../shared/data/real/dev), THREADS (torch threads, default 2), LOADER_WORKERS
# (example-building processes, default 0: on a 2-core machine a worker beside 2 torch threads slowed
# training ~2x; the batches are the same for any number),
# PROBE_CONFIG (segmenter config for every probe; default configs/segmenter-pre-ema.yaml, the recipe
# of the published tables; "" for today's defaults), HYBRID=1 to score every generated-data model with
# hybrid inference too (`probe --hybrid`: a second row per generator in the table),
# SKIP_REAL=1 to leave out the leave-one-room-out rows; TSDF=1 adds "assist3d-tsdf": the ASSIST-3D
# preset with render.point_source=tsdf (ScanNet-like reconstructed surfaces; needs the [sim] extra),
# the same scenes as "assist3d" (same seed and layouts), only the points differ.
set -euo pipefail

OUT=${1:?usage: scripts/fidelity.sh OUT_DIR}
STEPS=${STEPS:-600}
SEEDS=${SEEDS:-3}
SCENES=${SCENES:-60}
GENERATORS=${GENERATORS:-"assist3d randomrooms holodeck-style no-context mesh-sampled"}
HERE="$(cd "$(dirname "$0")/.." && pwd)"
DEV=${DEV:-$HERE/../shared/data/real/dev}
THREADS=${THREADS:-2}
LOADER_WORKERS=${LOADER_WORKERS:-0}
PROBE_CONFIG=${PROBE_CONFIG-$HERE/configs/segmenter-pre-ema.yaml}
CONFIG_ARGS=()
if [[ -n "$PROBE_CONFIG" ]]; then CONFIG_ARGS=(--config "$PROBE_CONFIG"); fi
HYBRID_ARGS=()
if [[ "${HYBRID:-0}" == 1 ]]; then HYBRID_ARGS=(--hybrid); fi
if [[ -z "${ASSIST3D:-}" ]]; then
  if command -v assist3d >/dev/null 2>&1; then ASSIST3D=assist3d; else ASSIST3D="$HERE/.venv/bin/assist3d"; fi
fi
ASSET_ARGS=()
if [[ -n "${ASSETS:-}" ]]; then ASSET_ARGS=(--assets "$ASSETS"); fi
mkdir -p "$OUT/data" "$OUT/probe"

for g in $GENERATORS; do
  "$ASSIST3D" generate --out "$OUT/data/$g" --num-scenes "$SCENES" --seed 0 --preset "$g" --workers 2 \
    ${ASSET_ARGS[@]+"${ASSET_ARGS[@]}"} --json > "$OUT/data/$g.generate.json"
done

PROBED="$GENERATORS"
if [[ "${TSDF:-0}" == 1 ]]; then
  printf 'render:\n  point_source: tsdf\n' > "$OUT/data/tsdf.yaml"
  "$ASSIST3D" generate --out "$OUT/data/assist3d-tsdf" --num-scenes "$SCENES" --seed 0 --preset assist3d --workers 2 \
    --config "$OUT/data/tsdf.yaml" ${ASSET_ARGS[@]+"${ASSET_ARGS[@]}"} --json > "$OUT/data/assist3d-tsdf.generate.json"
  PROBED="$PROBED assist3d-tsdf"
fi

# seed by seed across generators (a probe folder resumes and only adds the missing seeds), so a run
# cut short leaves every generator with the same number of seeds
for k in $(seq 1 "$SEEDS"); do
  for g in $PROBED; do
    "$ASSIST3D" probe --train "assist3d:$OUT/data/$g" --eval "array:$DEV" --steps "$STEPS" --seeds "$k" \
      --threads "$THREADS" --loader-workers "$LOADER_WORKERS" ${CONFIG_ARGS[@]+"${CONFIG_ARGS[@]}"} ${HYBRID_ARGS[@]+"${HYBRID_ARGS[@]}"} --out "$OUT/probe/$g" --json > "$OUT/probe/$g.json"
    echo "probe $g: $k seed(s) done" >&2
  done
done

# the non-learned reference
"$ASSIST3D" segment "array:$DEV" --method geometric --out "$OUT/probe/geometric/pred" > /dev/null
"$ASSIST3D" evaluate --gt "array:$DEV" --pred "$OUT/probe/geometric/pred" --json --per-scene > "$OUT/probe/geometric.json"

# real-only: leave one room out (rescans of a room share the first 9 characters of their name)
if [[ "${SKIP_REAL:-0}" != 1 ]]; then
  rooms=$(ls "$DEV"/*.npy | xargs -n1 basename | cut -c1-9 | sort -u)
  for r in $rooms; do
    train_args=(); eval_args=()
    for f in "$DEV"/*.npy; do
      if [[ "$(basename "$f" | cut -c1-9)" == "$r" ]]; then eval_args+=(--eval "array:$f"); else train_args+=(--train "array:$f"); fi
    done
    "$ASSIST3D" probe "${train_args[@]}" "${eval_args[@]}" --steps "$STEPS" --seeds "$SEEDS" --threads "$THREADS" \
      --loader-workers "$LOADER_WORKERS" ${CONFIG_ARGS[@]+"${CONFIG_ARGS[@]}"} --out "$OUT/probe/real-loro/$r" --json > "$OUT/probe/real-loro/$r.json"
  done
fi

PY="$HERE/.venv/bin/python"; [[ -x "$PY" ]] || PY=python3
"$PY" "$HERE/scripts/fidelity_table.py" "$OUT" "$DEV" | tee "$OUT/table.md"
