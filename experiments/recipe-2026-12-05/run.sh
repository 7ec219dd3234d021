#!/usr/bin/env bash
# The paper's recipe at small scale, leave one room out (plan.md). Resumable: a probe keeps its finished seeds
# and resumes an unfinished one from its last.pt; re-run the same command to continue.
#   experiments/recipe-2026-12-05/run.sh OUT          (from the repository root)
# OUT/data/assist3d: the scaling study's 250 ASSIST-3D scenes (a symlink or folder; generated when missing);
# OUT/data/randomrooms: generated here. ARMS (default "mix-assist3d real synth mix-randomrooms"), SEEDS
# (default "0 1 2"), SYNTH_SEEDS (default "2": seeds 0 and 1 of the synth arm are the scaling study's
# probe-s250-t200 runs, the same training), STEPS (200), ASSIST3D (the command), DEV (the dev scans), DEVICE (cpu).
set -euo pipefail
OUT=${1:?usage: run.sh OUT}
ARMS=${ARMS:-mix-assist3d real synth mix-randomrooms}
SEEDS=${SEEDS:-0 1 2}
STEPS=${STEPS:-200}
A=${ASSIST3D:-assist3d}
DEV=${DEV:-../shared/data/real/dev}
DEVICE=${DEVICE:-cpu}
mkdir -p "$OUT/data"
data() {  # data PRESET: make sure OUT/data/PRESET holds 250 scenes of that preset (seed 0)
  $A generate --out "$OUT/data/$1" --num-scenes 250 --seed 0 --preset "$1" --workers 2 --rays full --json \
    > "$OUT/generate-$1.json" 2> "$OUT/generate-$1.log"
}
rooms=$(ls "$DEV"/*.npy | xargs -n1 basename | cut -c1-9 | sort -u)
probe() {  # probe DIR SEED ARGS...: one seed of one probe
  local dir=$1 seed=$2; shift 2
  date -u; echo "probe $dir seed $seed"
  $A probe "$@" --steps "$STEPS" --seeds 1 --first-seed "$seed" --max-train-scenes 250 --threads 2 \
    --device "$DEVICE" --out "$OUT/$dir" --json > "$OUT/$dir-seed$seed.json" 2> "$OUT/$dir-seed$seed.log"
}
for arm in $ARMS; do
  case $arm in
    synth) data assist3d
      all_eval=(); for f in "$DEV"/*.npy; do all_eval+=(--eval "array:$f"); done
      for k in ${SYNTH_SEEDS:-2}; do probe synth "$k" --train "assist3d:$OUT/data/assist3d" "${all_eval[@]}"; done
      continue ;;
    mix-assist3d) data assist3d ;;
    mix-randomrooms) data randomrooms ;;
    real) ;;
    *) echo "unknown arm $arm" >&2; exit 2 ;;
  esac
  for k in $SEEDS; do
    for r in $rooms; do
      args=()
      for f in "$DEV"/*.npy; do
        if [[ "$(basename "$f" | cut -c1-9)" == "$r" ]]; then args+=(--eval "array:$f")
        else args+=(--train "array:$f" --weight 1); fi
      done
      if [[ $arm == mix-* ]]; then args+=(--train "assist3d:$OUT/data/${arm#mix-}" --weight 0.5); fi
      mkdir -p "$OUT/$arm"
      probe "$arm/$r" "$k" "${args[@]}"
    done
  done
done
date -u; echo DONE
