#!/usr/bin/env bash
# geometry_diversity_se against the gap between two generation seeds (plan.md). C: the Sweet Home 3D + procedural
# catalog; D: the scratch folder holding cmp50s0/ and cmp50s1/ (scripts/compare_generators.sh, as in
# experiments/geometry-seeds-2026-12-01/run.sh)
set -eu
cd "$(dirname "$0")/../.."; source .venv/bin/activate
R=experiments/geometry-se-2026-12-01
assist3d metrics ${D:?}/cmp50s0/{assist3d,randomrooms,holodeck-style,no-context} \
  $D/cmp50s1/{assist3d,randomrooms,holodeck-style,no-context} --assets ${C:?} --seed 0 --json > $R/metrics-both-seeds.json
python $R/table.py $R/metrics-both-seeds.json
