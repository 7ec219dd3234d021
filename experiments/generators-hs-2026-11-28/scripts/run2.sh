#!/usr/bin/env bash
# after run.sh: no-refit hybrid figures of the six new models (plan.md), dev and scene0451_01
set -x
cd /work/main; source .venv/bin/activate
S=/work/scratch/s21; H=experiments/generators-hs-2026-11-28
while ! grep -q TRAINDONE $S/run.log; do sleep 30; done
date -u
M=""; for g in mesh-sampled randomrooms; do for k in 0 1 2; do M="$M $S/probe/$g-household-sparse/seed_$k/model.pt"; done; done
python scripts/hybrid_eval.py $M --eval array:/work/shared/data/real/dev --refine-planes 0 --threads 2 --out $S/hybrid-eval-dev-hs-r0.json > $S/he_dev.log 2>&1
date -u
python scripts/hybrid_eval.py $M --eval array:/work/shared/data/real/scannet_scene0451_01.npy --refine-planes 0 --threads 2 --out $S/hybrid-eval-s0451-hs-r0.json > $S/he_s0451.log 2>&1
date -u
echo HEDONE
