#!/usr/bin/env bash
# geometry diversity of the 702-class generator comparison at metric seeds 0-4 (plan.md)
# C: the Sweet Home 3D + procedural catalog; D: a scratch folder (datasets from scripts/compare_generators.sh)
set -eu
cd "$(dirname "$0")/../.."; source .venv/bin/activate
C=${C:?catalog}; D=${D:?scratch folder}; R=experiments/geometry-seeds-2026-12-01
for S in 0 1; do
  ASSETS=$C SEED=$S scripts/compare_generators.sh $D/cmp50s$S 50 12 > $R/compare-s$S.json
  for M in 0 1 2 3 4; do
    assist3d metrics $D/cmp50s$S/{assist3d,randomrooms,holodeck-style,no-context} --assets $C --seed $M --json \
      | python -c "import json,sys;r=json.load(sys.stdin);print(json.dumps({k.rsplit('/',1)[-1]:v['geometry_diversity'] for k,v in r.items()}))"
  done > $R/seeds-s$S.jsonl
done
# the same datasets listed in reverse: the same values (the codebook does not depend on list order)
assist3d metrics $D/cmp50s0/{no-context,holodeck-style,randomrooms,assist3d} --assets $C --json \
  | python -c "import json,sys;r=json.load(sys.stdin);print(json.dumps({k.rsplit('/',1)[-1]:v['geometry_diversity'] for k,v in r.items()}))" > $R/reversed-s0.json
python $R/table.py $R
