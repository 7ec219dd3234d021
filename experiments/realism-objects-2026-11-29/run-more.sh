#!/usr/bin/env bash
# The other generator presets of docs/metrics.md's realism table (no-context, mesh-sampled, ASSIST-3D sparser),
# 50 scenes each, seed 0, the combo catalog, scored against both readings of the real dev scans like run.sh.
# The sparser set uses the selection counts of the old table (15 floor, 8 wall, 2 on-top candidates).
cd "$(dirname "$0")/../.."; source .venv/bin/activate
D=${D:?scratch folder}; LIB=${ASSETS:?the Sweet Home 3D + procedural catalog}; mkdir -p $D
cp experiments/fidelity-2026-11-25/assist3d-sparse/sparse.yaml $D/sparser.yaml
date -u
assist3d generate --out $D/no-context --num-scenes 50 --seed 0 --preset no-context --assets $LIB --workers 2 --json > $D/gen-nc.json 2> $D/gen-nc.log || exit 1
assist3d generate --out $D/mesh-sampled --num-scenes 50 --seed 0 --preset mesh-sampled --assets $LIB --workers 2 --json > $D/gen-ms.json 2> $D/gen-ms.log || exit 1
assist3d generate --out $D/sparser --num-scenes 50 --seed 0 --preset assist3d --config $D/sparser.yaml --assets $LIB --workers 2 --json > $D/gen-sp.json 2> $D/gen-sp.log || exit 1
date -u
SETS="assist3d:$D/no-context assist3d:$D/mesh-sampled assist3d:$D/sparser"
python scripts/realism_reference.py 'array:../shared/data/real/dev?objects=benchmark' --score $SETS --max-scenes 50 > $D/realism-benchmark-objects.txt
python scripts/realism_reference.py 'array:../shared/data/real/dev?objects=annotated' --loro --score $SETS --max-scenes 50 --matched 200 --json > $D/realism-annotated-matched.json
python - $D/realism-annotated-matched.json > $D/realism-annotated.txt <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
for spec, v in r["scores"].items():
    print(spec, v["layout_realism"], f"({v['objects']} objects)", v["components"])
print("at each held-out room's size (mean over draws +- their std), per room and mean over rooms:")
for spec, v in r["matched"]["datasets"].items():
    print(spec, v["mean"], {k: f"{x['mean']}+-{x['std']}" for k, x in v["rooms"].items()})
PY
date -u; echo DONE
