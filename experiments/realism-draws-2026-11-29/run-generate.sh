#!/usr/bin/env bash
# a second draw of the preset datasets: as experiments/realism-presets-2026-11-29/run.sh, --seed 1
cd "$(dirname "$0")/../.."; source .venv/bin/activate
D=${D:?output folder}; mkdir -p $D
for p in assist3d randomrooms holodeck-style; do
  date -u; echo $p
  assist3d generate --out $D/$p --num-scenes 50 --seed 1 --workers 2 --preset $p --assets ${ASSETS:?the Sweet Home 3D + procedural catalog} --json > $D/gen-$p.json 2> $D/gen-$p.log || exit 1
done
date -u; echo DONE
