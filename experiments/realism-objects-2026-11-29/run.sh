#!/usr/bin/env bash
# plan.md of this folder: the preset datasets scored against the real dev scans read with every annotated object
# (the new shipped reference) and, for comparison, with the 18 benchmark classes only (the old one; since
# realism_spec, a spec without ?objects= is read with every annotated object, so the old reading is named).
# Datasets: D=... made by experiments/realism-presets-2026-11-29/run.sh (50 scenes a preset, seed 0, combo catalog).
cd "$(dirname "$0")/../.."; source .venv/bin/activate
D=${D:?folder holding assist3d/ randomrooms/ holodeck-style/}; OUT=${OUT:-$D}
SETS="assist3d:$D/assist3d assist3d:$D/randomrooms assist3d:$D/holodeck-style"
NEW='array:../shared/data/real/dev?objects=annotated'; OLD='array:../shared/data/real/dev?objects=benchmark'
date -u
python scripts/realism_reference.py "$OLD" --score $SETS --max-scenes 50 > $OUT/realism-benchmark-objects.txt
python scripts/realism_reference.py "$NEW" --score $SETS --max-scenes 50 > $OUT/realism-annotated-objects.txt
python scripts/realism_reference.py "$NEW" --loro --score $SETS --max-scenes 50 --matched 200 --json > $OUT/realism-annotated-matched.json
python - $OUT/realism-annotated-matched.json > $OUT/realism-annotated-matched.txt <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print("real rooms, each against the others:", {k: v["layout_realism"] for k, v in r["loro"].items()}, "mean", r["loro_mean"])
print("at each held-out room's size (mean over draws +- their std), per room and mean over rooms:")
for spec, v in r["matched"]["datasets"].items():
    print(spec, v["mean"], {k: f"{x['mean']}+-{x['std']}" for k, x in v["rooms"].items()})
PY
date -u; echo DONE
