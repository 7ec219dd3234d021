#!/usr/bin/env bash
# layout_realism and its scene-bootstrap standard error of the seed-0 (D0) and seed-1 (D1) preset sets, against
# the real dev scans read with every annotated object (the shipped reference's reading)
cd "$(dirname "$0")/../.."; source .venv/bin/activate
D0=${D0:?seed-0 preset datasets}; D1=${D1:?seed-1 preset datasets}; O=${O:?output folder}; mkdir -p $O
date -u
python scripts/realism_reference.py 'array:../shared/data/real/dev' --max-scenes 50 --json --score \
  assist3d:$D0/assist3d assist3d:$D0/randomrooms assist3d:$D0/holodeck-style \
  assist3d:$D1/assist3d assist3d:$D1/randomrooms assist3d:$D1/holodeck-style > $O/scores.json 2> $O/scores.err
echo "rc $?"; date -u
python - $O/scores.json <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["scores"]
for spec, v in r.items():
    print(f"{spec}: {v['layout_realism']} +- {v['layout_realism_se']}  ({v['scenes']} scenes, {v['objects']} objects)")
PY
