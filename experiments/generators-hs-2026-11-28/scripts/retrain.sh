#!/usr/bin/env bash
# generators-hs plan amendment 2: ASSIST-3D household-sparse seeds 0-1 retrained, then scene0451_01
set -x
cd /work/main; source .venv/bin/activate
S=/work/scratch/s21; D=/work/scratch/s20/data/assist3d-household-sparse
while ! grep -q "^RC " $S/ci.log; do sleep 10; done
date -u
assist3d probe --train assist3d:$D --eval array:/work/shared/data/real/dev --steps 200 --seeds 2 --threads 2 --loader-workers 0 --out $S/retrain/assist3d-household-sparse --json > $S/retrain.json 2> $S/retrain.log
date -u
python scripts/hybrid_eval.py $S/retrain/assist3d-household-sparse/seed_0/model.pt $S/retrain/assist3d-household-sparse/seed_1/model.pt --eval array:/work/shared/data/real/scannet_scene0451_01.npy --refine-planes 0 --threads 2 --out $S/hybrid-eval-s0451-hs-A01-r0.json > $S/he_A01.log 2>&1
date -u
echo RTDONE
