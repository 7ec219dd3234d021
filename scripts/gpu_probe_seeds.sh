#!/usr/bin/env bash
# Train probe seeds side by side on one GPU machine and send each seed back as one file.
#
#   bash scripts/gpu_probe_seeds.sh TRAIN EVAL STEPS "SEEDS" [PARALLEL] [CONFIG]
#
# e.g. (device machine, repo root):  bash scripts/gpu_probe_seeds.sh array:/tmp/d/hs \
#        array:.devcheck/gen_scene.npy 821 "1 2 3 4" 4
#
# Runs `scripts/device_setup.sh` (carried wheels and packed data, see there), then one
# `assist3d probe --seeds 1 --first-seed S --device cuda` process per seed, PARALLEL (default 4) at
# a time, each into its own folder. Measured on an H200 (experiments/fidelity-log.md, "Speed of the probe on a
# GPU"): one process trains 821 steps in 165 s, four at once 376-381 s each, three 309-310 s each.
# Each seed comes back as $OUT/seedS.tar holding probe.json and seed_S/ (model.pt, result.json,
# train_log.csv, probe.log): the device tool returns at most 8 files (16 MiB each), so at most 8
# seeds a call. Here: `for f in FILES_AT/seed*.tar; do tar xf "$f" -C DIR; done` makes DIR a probe
# folder; `assist3d probe` with the same request, `--out DIR` and the same seeds (for "1 2 3 4":
# `--first-seed 1 --seeds 4`) then reads every seed back.
# DEVICE (default cuda) and EXTRA (more probe options) in the environment allow a dry run on a CPU:
#   OUT=/tmp/o DEVICE=cpu WHEELS=0 EXTRA="--max-train-scenes 2" bash scripts/gpu_probe_seeds.sh ... 2 "0 1" 2
set -u
DEVICE=${DEVICE:-cuda} EXTRA=${EXTRA:-}
if (( $# < 4 )); then
  sed -n 2,19p "$0"; exit 2
fi
TRAIN=$1 EVAL=$2 STEPS=$3 SEEDS=$4 PARALLEL=${5:-4} CONFIG=${6:-}
read -r -a seeds <<< "$SEEDS"
if ! [[ "$PARALLEL" =~ ^[1-9][0-9]*$ ]]; then
  echo "PARALLEL must be a positive integer, not '$PARALLEL'" >&2; exit 2
fi
if (( ${#seeds[@]} > 8 )); then
  echo "at most 8 seeds a call (the device tool returns at most 8 files)" >&2; exit 2
fi
: "${OUT:?OUT is not set: this runs on the device machine, whose OUT folder comes back}"
. scripts/device_setup.sh
nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null || echo "no nvidia-smi"
one_seed() {
  local s=$1 dir=/tmp/gp/p$1 t0
  t0=$(date +%s)
  python3 -m assist3d probe --train "$TRAIN" --eval "$EVAL" --steps "$STEPS" --seeds 1 --first-seed "$s" \
    --device "${DEVICE:-cuda}" --threads 2 --loader-workers $(( 12 / PARALLEL > 1 ? 12 / PARALLEL : 1 )) \
    ${CONFIG:+--config "$CONFIG"} ${EXTRA:-} --out "$dir" --json > "$dir.json" 2> "$dir.log"
  local rc=$?
  echo "seed $s rc=$rc $(( $(date +%s) - t0 )) s $(tail -1 "$dir/seed_$s/train_log.csv" 2>/dev/null | cut -d, -f1,2)"
  cp "$dir.log" "$dir/seed_$s/probe.log" 2>/dev/null
  tar cf "$OUT/seed$s.tar" -C "$dir" probe.json "seed_$s/model.pt" "seed_$s/result.json" \
    "seed_$s/train_log.csv" "seed_$s/probe.log" 2>/dev/null || { echo "seed $s: incomplete, see $dir.log"; return 1; }
  return $rc
}
export -f one_seed
export TRAIN EVAL STEPS PARALLEL CONFIG OUT DEVICE EXTRA
mkdir -p /tmp/gp "$OUT"
rc=0
printf '%s\n' "${seeds[@]}" | xargs -P "$PARALLEL" -I{} bash -c 'one_seed "$1"' _ {} || rc=1
ls -la "$OUT"
exit $rc
