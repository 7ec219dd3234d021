#!/usr/bin/env bash
# generators-hs-821-2026-11-28/plan.md: the household-sparse baselines at 821 steps, seeds in the plan's order
cd /work/main; source .venv/bin/activate
S=/work/scratch/s21; DEV=/work/shared/data/real/dev; O=$S/probe821
for k in 0 1 2; do
  for g in mesh-sampled randomrooms; do
    echo "$g seed $k start $(date -u)"
    assist3d probe --train assist3d:$S/data/$g-household-sparse --eval array:$DEV --steps 821 --seeds $((k+1)) --threads 2 --loader-workers 0 --out $O/$g-household-sparse --json > $O/$g.json 2> $O/$g-$k.log
    echo "$g seed $k done $(date -u)"
  done
done
