#!/usr/bin/env bash
# ship-candidate plan amendment: the recipe's third seed (2), then its six evaluations into cand2-eval/
cd /work/main; source .venv/bin/activate
S=/work/scratch/s21; DEV=/work/shared/data/real/dev; O=$S/cand2-eval; mkdir -p $O
D=/work/scratch/s20/data/assist3d-household-sparse
echo "start $(date -u)"
mkdir -p $S/ship-cand2/seed_0 $S/ship-cand2/seed_1
cp /work/scratch/s20/ship-cand/seed_0/result.json $S/ship-cand2/seed_0/
cp /work/scratch/s20/ship-cand1/seed_1/result.json $S/ship-cand2/seed_1/
assist3d probe --train assist3d:$D --eval array:$DEV --steps 821 --seeds 3 --threads 2 --loader-workers 0 --out $S/ship-cand2 --json > $S/ship-cand2.json 2> $S/ship-cand2.log
echo "trained $(date -u)"
M=$S/ship-cand2/seed_2/model.pt
python experiments/tools/noise_robustness.py --model $M --sigma 0 --methods learned hybrid --threads 2 --out $O/r2-clean.json
for s in 0 1 2 3 4; do
  python experiments/tools/noise_robustness.py --model $M --sigma 0.001 --seed $s --methods learned hybrid --threads 2 --out $O/r2-1mm-seed$s.json
done
echo "done $(date -u)"
