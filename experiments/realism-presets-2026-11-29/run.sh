#!/usr/bin/env bash
# (2026-11-29 later: '?objects=benchmark' pins the reading these figures were made with; the realism code now reads
# real scans with every annotated object unless told so: experiments/realism-objects-2026-11-29)
# the preset realism table of docs/metrics.md again on today's code: 50 scenes per preset, seed 0, combo catalog
cd "$(dirname "$0")/../.."; source .venv/bin/activate
D=${D:-/tmp/realism-presets}; mkdir -p $D
for p in assist3d randomrooms holodeck-style; do
  date -u; echo $p
  assist3d generate --out $D/$p --num-scenes 50 --seed 0 --workers 2 --preset $p --assets ${ASSETS:?the Sweet Home 3D + procedural catalog} --json > $D/gen-$p.json 2> $D/gen-$p.log || exit 1
done
date -u
python scripts/realism_reference.py 'array:../shared/data/real/dev?objects=benchmark' --score assist3d:$D/assist3d assist3d:$D/randomrooms assist3d:$D/holodeck-style --max-scenes 50 > $D/realism.txt 2> $D/realism.err
date -u; echo DONE
