#!/usr/bin/env bash
# the probe on CUDA, new code (fused per-scene normalisation) against the frozen code, same data and steps
. scripts/device_setup.sh
ls /tmp/d; nvidia-smi --query-gpu=name --format=csv,noheader
for v in new old; do
  if [ $v = new ]; then export PYTHONPATH=/tmp/site:$PWD/src; else export PYTHONPATH=/tmp/site:$PWD/.devcheck/frozen_src; fi
  python3 -c "import assist3d; print('$v', assist3d.__file__)"
  rm -rf /tmp/p-$v
  t0=$(date +%s)
  timeout 150 python3 -m assist3d probe --train array:/tmp/d/hs --eval array:.devcheck/gen_scene.npy --steps 100 --device cuda --threads 2 --loader-workers 12 --out /tmp/p-$v --json > $OUT/probe-$v.json 2> $OUT/probe-$v.err
  echo "$v rc=$? wall $(( $(date +%s) - t0 )) s"
  tail -1 /tmp/p-$v/seed_0/train_log.csv
  cp /tmp/p-$v/seed_0/train_log.csv $OUT/train_log-$v.csv 2>/dev/null
done
