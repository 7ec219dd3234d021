#!/usr/bin/env bash
# generators-hs-2026-11-28/plan.md
set -x
cd /work/main; source .venv/bin/activate
S=/work/scratch/s21; H=experiments/generators-hs-2026-11-28; HW=experiments/holodeck-why-2026-11-28; DEV=/work/shared/data/real/dev
LIB=/work/scratch/combo-lib
date -u
assist3d generate --out $S/data/mesh-sampled-household-sparse --num-scenes 60 --seed 0 --preset mesh-sampled --config $HW/household-sparse.yaml --assets $LIB --workers 2 --json > $S/data-mesh.json 2> $S/genM.log
date -u
assist3d generate --out $S/data/randomrooms-household-sparse --num-scenes 60 --seed 0 --preset randomrooms --config $H/rr-household-sparse.yaml --assets $LIB --workers 2 --json > $S/data-rr.json 2> $S/genR.log
date -u
for k in 0 1 2; do
  for g in mesh-sampled randomrooms; do
    assist3d probe --train assist3d:$S/data/$g-household-sparse --eval array:$DEV --steps 200 --seeds $((k+1)) --threads 2 --loader-workers 0 --out $S/probe/$g-household-sparse --json > $S/probe-$g.json 2> $S/probe-$g-$k.log
    date -u
  done
done
echo TRAINDONE
