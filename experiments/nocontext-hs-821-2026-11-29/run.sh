#!/usr/bin/env bash
# nocontext-hs-821-2026-11-29/plan.md: three 821-step seeds of the no-context household-sparse data, each
# followed by its six evaluations. Resumable. S: scratch folder holding the dataset (../nocontext-hs-2026-11-29/run.sh).
S=${S:-/work/scratch/s24}; DEV=${DEV:-/work/shared/data/real/dev}
cd "$(dirname "$0")/../.."; source .venv/bin/activate
D=experiments/nocontext-hs-821-2026-11-29; DATA=$S/data/no-context-household-sparse; O=$S/probe821/no-context-household-sparse-821
[ -f $DATA/manifest.json ] || { echo "no dataset at $DATA: run ../nocontext-hs-2026-11-29/run.sh first"; exit 1; }
for k in 0 1 2; do
  date -u; echo "seed $k"
  assist3d probe --train assist3d:$DATA --eval array:$DEV --steps 821 --seeds $((k+1)) --threads 2 --loader-workers 0 \
    --out $O --json > $S/probe821-nc.json 2> $S/probe821-nc-$k.log || exit 1
  mkdir -p $D/per_seed && cp $O/seed_$k/result.json $D/per_seed/no-context-household-sparse-seed$k.json
  E=$D/eval/no-context-$k; mkdir -p $E; M=$O/seed_$k/model.pt
  [ -f $E/r2-clean.json ] || python experiments/tools/noise_robustness.py --model $M --sigma 0 --methods learned hybrid --threads 2 --out $E/r2-clean.json
  for s in 0 1 2 3 4; do
    [ -f $E/r2-1mm-seed$s.json ] || python experiments/tools/noise_robustness.py --model $M --sigma 0.001 --seed $s --methods learned hybrid --threads 2 --out $E/r2-1mm-seed$s.json
  done
done
echo ALLDONE; date -u
