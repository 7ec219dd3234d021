#!/usr/bin/env bash
# plan.md: generate both arms (60 scenes, seed 0), then probe seeds in alternation; a finished seed is skipped by
# the probe, so the script can be run again to continue. C: the combo catalog; S: a scratch folder.
set -eu
cd "$(dirname "$0")/../.."; source .venv/bin/activate
HERE=experiments/placement-probe-2026-12-01
for arm in guided random; do
  cfg=$HERE/household-sparse.yaml; [ $arm = random ] && cfg=$HERE/household-sparse-random.yaml
  assist3d generate --out ${S:?}/data/$arm --num-scenes 60 --seed 0 --preset assist3d --config $cfg \
    --assets ${C:?} --workers 2 --json > $S/gen-$arm.json 2> $S/gen-$arm.log
done
for k in ${SEEDS:-0 1 2}; do for arm in guided random; do
  date -u; echo "probe $arm seed $k"
  assist3d probe --train assist3d:$S/data/$arm --eval array:../shared/data/real/dev --steps 200 --seeds 1 \
    --first-seed $k --threads 2 --loader-workers 0 --out $S/probe/$arm --json > $S/probe-$arm-$k.json 2> $S/probe-$arm-$k.log
  mkdir -p $HERE/per_seed && cp $S/probe/$arm/seed_$k/result.json $HERE/per_seed/$arm-seed$k.json
done; done
date -u; echo DONE
