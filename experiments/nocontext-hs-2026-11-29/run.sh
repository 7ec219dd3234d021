#!/usr/bin/env bash
# nocontext-hs-2026-11-29/plan.md: generate the no-context household-sparse dataset, probe seeds 0-2, score
# scene0451_01. Resumable: generation and probe skip what is done. S: scratch folder (datasets, probe).
S=${S:-/work/scratch/s24}; LIB=${LIB:-/work/scratch/combo-lib}; DEV=${DEV:-/work/shared/data/real/dev}
cd "$(dirname "$0")/../.."; source .venv/bin/activate
D=experiments/nocontext-hs-2026-11-29; DATA=$S/data/no-context-household-sparse; O=$S/probe/no-context-household-sparse
date -u
[ -f $DATA/manifest.json ] || assist3d generate --out $DATA --num-scenes 60 --seed 0 --preset no-context \
  --config configs/household-sparse.yaml --assets $LIB --workers 2 --json > $S/gen-nc.json 2> $S/gen-nc.log
date -u
for k in 0 1 2; do
  assist3d probe --train assist3d:$DATA --eval array:$DEV --steps 200 --seeds $((k+1)) --threads 2 --loader-workers 0 \
    --hybrid --out $O --json > $S/probe-nc.json 2> $S/probe-nc-$k.log
  mkdir -p $D/per_seed && cp $O/seed_$k/result.json $D/per_seed/no-context-household-sparse-seed$k.json
  date -u
done
for k in 0 1 2; do
  [ -f $D/s0451-seed$k.json ] || python experiments/tools/noise_robustness.py --model $O/seed_$k/model.pt --sigma 0 \
    --methods learned hybrid --threads 2 --out $D/s0451-seed$k.json > $S/s0451-$k.log 2>&1
done
echo ALLDONE; date -u
