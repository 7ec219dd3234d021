#!/usr/bin/env bash
# On a lent GPU machine (the device tool's `run`, carry [".whl", ".devdata"], from the repository root):
# bench-train on CUDA in both convolution paths (float32 per-offset gather-matmul-scatter; bfloat16 im2col), with and
# without loader workers, and the same machine's CPU on 2 threads, all on the 8 scenes prepare.sh packed. Every
# figure is one JSON in $OUT. About 5 minutes; each arm has its own timeout so that one slow arm cannot eat the lease.
. scripts/device_setup.sh            # wheels into /tmp/site, .devdata/hs8.npz.xz -> $DATA/hs8 (default /tmp/d)
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader > "$OUT/gpu.txt" 2>&1
python3 -c "import torch; print(torch.__version__, torch.version.cuda, torch.cuda.is_available())" >> "$OUT/gpu.txt"
DEVICE=${DEVICE:-cuda} STEPS=${STEPS:-30}
arm() {  # arm NAME DEVICE PRECISION LOADER_WORKERS LIMIT_S
  local t0=$(date +%s)
  timeout "$5" python3 -m assist3d bench-train --data "array:${DATA:-/tmp/d}/hs8" --steps "$STEPS" --warmup 5 --device "$2" \
    --precision "$3" --loader-workers "$4" --threads 2 --json > "$OUT/$1.json" 2> "$OUT/$1.err"
  echo "$1: rc=$? $(( $(date +%s) - t0 )) s  $(grep -o '"step_s_median": [0-9.]*' "$OUT/$1.json")"
}
arm cuda-f32-lw0 "$DEVICE" float32 0 90
arm cuda-f32-lw6 "$DEVICE" float32 6 90
arm cuda-bf16-lw6 "$DEVICE" bfloat16 6 90
arm cuda-f32-lw12 "$DEVICE" float32 12 90
arm cpu-2threads cpu auto 0 150
