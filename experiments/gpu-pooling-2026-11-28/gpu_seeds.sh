#!/usr/bin/env bash
# plan.md beside this file: seeds 1-4 of the ship-candidate recipe on one GPU, four processes at once.
# Needs (carried, untracked): .whl/ (pydantic & co.), .devdata/hs.npz.xz (scripts/pack_scenes.py of the
# household-sparse ASSIST-3D dataset), .devcheck/gen_scene.npy (one generated scene, the probe's --eval).
. scripts/device_setup.sh
nvidia-smi --query-gpu=name,memory.used --format=csv,noheader
python3 -c "import torch; print(torch.__version__, torch.version.cuda)"
t0=$(date +%s)
pids=()
for s in 1 2 3 4; do
  ( timeout ${LIMIT:-470} python3 -m assist3d probe --train array:/tmp/d/hs --eval array:.devcheck/gen_scene.npy \
      --steps 821 --seeds 1 --first-seed $s --device cuda --threads 2 --loader-workers 3 --out /tmp/p$s --json \
      > $OUT/probe-$s.json 2> $OUT/probe-$s.err
    echo "seed $s rc=$? at $(( $(date +%s) - t0 )) s"
    mkdir -p $OUT/seed$s
    cp /tmp/p$s/seed_$s/{model.pt,result.json,train_log.csv} $OUT/seed$s/ 2>/dev/null ) &
  pids+=($!)
done
( while sleep 60; do for s in 1 2 3 4; do echo "t=$(( $(date +%s) - t0 )) seed $s $(tail -1 /tmp/p$s/seed_$s/train_log.csv 2>/dev/null | cut -d, -f1,2)"; done; done ) &
watch=$!
wait "${pids[@]}"
pkill -P $watch; kill $watch 2>/dev/null
nvidia-smi --query-gpu=memory.used --format=csv,noheader
ls -la $OUT/seed*
