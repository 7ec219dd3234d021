#!/usr/bin/env bash
# plan-eval-spread.md, amendment: nine household-sparse 200-step models, clean and five 1 mm draws, dev scans
cd /work/main; source .venv/bin/activate
DEV=array:/work/shared/data/real/dev; O=experiments/noise-2026-11-28/spread2; mkdir -p $O
declare -A M=(
  [assist3d-2]=/work/scratch/s20/probe/assist3d-household-sparse/seed_2/model.pt
  [assist3d-0]=/work/scratch/s21/retrain/assist3d-household-sparse/seed_0/model.pt
  [assist3d-1]=/work/scratch/s21/retrain/assist3d-household-sparse/seed_1/model.pt)
for g in mesh-sampled randomrooms; do for k in 0 1 2; do
  M[$g-$k]=/work/scratch/s21/probe/$g-household-sparse/seed_$k/model.pt; done; done
echo "start $(date -u)"
for key in assist3d-0 assist3d-1 assist3d-2 mesh-sampled-0 mesh-sampled-1 mesh-sampled-2 randomrooms-0 randomrooms-1 randomrooms-2; do
  m=${M[$key]}
  python experiments/tools/noise_robustness.py --model $m --sigma 0 --methods learned hybrid --refine-planes 0 --eval $DEV --threads 2 --out $O/$key-clean.json
  for s in 0 1 2 3 4; do
    python experiments/tools/noise_robustness.py --model $m --sigma 0.001 --seed $s --methods learned hybrid --refine-planes 0 --eval $DEV --threads 2 --out $O/$key-seed$s.json
  done
done
echo "done $(date -u)"
