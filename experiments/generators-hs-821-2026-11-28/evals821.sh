#!/usr/bin/env bash
# generators-hs-821-2026-11-28/plan.md, amendment: the six evaluations of every finished baseline model
cd /work/main; source .venv/bin/activate
S=/work/scratch/s21/probe821; E=experiments/generators-hs-821-2026-11-28/eval
for g in mesh-sampled randomrooms; do for k in 0 1 2; do
  M=$S/$g-household-sparse/seed_$k/model.pt; O=$E/$g-$k
  [ -f $S/$g-household-sparse/seed_$k/result.json ] || continue
  mkdir -p $O
  [ -f $O/r2-clean.json ] || python experiments/tools/noise_robustness.py --model $M --sigma 0 --methods learned hybrid --threads 2 --out $O/r2-clean.json
  for s in 0 1 2 3 4; do
    [ -f $O/r2-1mm-seed$s.json ] || python experiments/tools/noise_robustness.py --model $M --sigma 0.001 --seed $s --methods learned hybrid --threads 2 --out $O/r2-1mm-seed$s.json
  done
done; done
