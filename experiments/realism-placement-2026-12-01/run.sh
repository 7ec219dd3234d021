#!/usr/bin/env bash
# random vs relation-guided placement of each generator's own objects (plan.md). Needs the combo catalog (C) and
# the seed-0 / seed-1 preset sets of the issue-14 acceptance run (P, P1: PRESET/ folders of 50 scenes each).
set -eu
cd "$(dirname "$0")/../.."; source .venv/bin/activate
HERE=experiments/realism-placement-2026-12-01
D=${D:-/tmp/realism-placement}; mkdir -p $D
for s in 0 1; do for p in assist3d holodeck-style; do
  date -u; echo "generate $p seed $s, random placement"
  assist3d generate --out $D/$p-random-s$s --num-scenes 50 --seed $s --workers 2 --preset $p \
    --config $HERE/random-placement.yaml --assets ${C:?combo catalog} --json > $D/gen-$p-s$s.json 2> $D/gen-$p-s$s.log
done; done
date -u
python scripts/realism_reference.py 'array:../shared/data/real/dev' --max-scenes 50 --score \
  assist3d:${P:?seed-0 presets}/assist3d assist3d:$D/assist3d-random-s0 \
  assist3d:$P/holodeck-style assist3d:$D/holodeck-style-random-s0 assist3d:$P/randomrooms \
  assist3d:${P1:?seed-1 presets}/assist3d assist3d:$D/assist3d-random-s1 \
  assist3d:$P1/holodeck-style assist3d:$D/holodeck-style-random-s1 assist3d:$P1/randomrooms > $D/realism.txt 2> $D/realism.err
cp $D/realism.txt $HERE/
date -u; echo DONE
