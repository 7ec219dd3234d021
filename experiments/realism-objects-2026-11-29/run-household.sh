#!/usr/bin/env bash
# Beyond plan.md: the household-class 50-scene sets of docs/metrics.md ("At equal vocabulary and object
# count"; the first 50 scenes of the 60-scene sets of generators-hs-2026-11-28 and holodeck-why-2026-11-28)
# made again and scored against both readings of the real dev scans.
cd "$(dirname "$0")/../.."; source .venv/bin/activate
D=${D:?scratch folder}; LIB=${ASSETS:?the Sweet Home 3D + procedural catalog}; mkdir -p $D
HW=experiments/holodeck-why-2026-11-28; H=experiments/generators-hs-2026-11-28
date -u
assist3d generate --out $D/assist3d-hs --num-scenes 50 --seed 0 --preset assist3d --config $HW/household-sparse.yaml --assets $LIB --workers 2 --json > $D/gen-a.json 2> $D/gen-a.log || exit 1
assist3d generate --out $D/randomrooms-hs --num-scenes 50 --seed 0 --preset randomrooms --config $H/rr-household-sparse.yaml --assets $LIB --workers 2 --json > $D/gen-r.json 2> $D/gen-r.log || exit 1
assist3d generate --out $D/holodeck-allmodels --num-scenes 50 --seed 0 --preset holodeck-style --config $HW/allmodels.yaml --assets $LIB --workers 2 --json > $D/gen-h.json 2> $D/gen-h.log || exit 1
date -u
SETS="assist3d:$D/assist3d-hs assist3d:$D/randomrooms-hs assist3d:$D/holodeck-allmodels"
python scripts/realism_reference.py 'array:../shared/data/real/dev?objects=benchmark' --score $SETS --max-scenes 50 > $D/realism-benchmark-objects.txt
python scripts/realism_reference.py 'array:../shared/data/real/dev?objects=annotated' --loro --score $SETS --max-scenes 50 --matched 200 --json > $D/realism-annotated-matched.json
python - $D/realism-annotated-matched.json > $D/realism-annotated.txt <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
for spec, v in r["scores"].items():
    print(spec, v["layout_realism"], f"({v['objects']} objects)", v["components"])
print("real rooms, each against the others:", {k: v["layout_realism"] for k, v in r["loro"].items()}, "mean", r["loro_mean"])
print("at each held-out room's size (mean over draws +- their std), per room and mean over rooms:")
for spec, v in r["matched"]["datasets"].items():
    print(spec, v["mean"], {k: f"{x['mean']}+-{x['std']}" for k, x in v["rooms"].items()})
PY
date -u; echo DONE
