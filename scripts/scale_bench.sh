#!/usr/bin/env bash
# Dataset throughput at paper settings (docs/scale.md, "Measured"): N scenes with --workers 2 on this machine,
# then the same N through --backend ray on a local two-node Ray cluster (head + one more node on 127.0.0.1,
# 1 CPU each), each timed whole by /usr/bin/time; the render is the default (the ray budget) unless RAYS=full.
#   scripts/scale_bench.sh OUT [N]     (from the repository root; needs the [ray] extra; N default 2000)
# BACKENDS="workers2 ray" (default) picks which of the two runs happen, in that order; a run whose .time
# file already holds a finished timing is not repeated.
set -euo pipefail
OUT=${1:?usage: scale_bench.sh OUT [N]}
N=${2:-2000}
A=${ASSIST3D:-assist3d}
RAY=${RAY:-$(dirname "$(command -v "$A" || echo .venv/bin/assist3d)")/ray}
RAYS=${RAYS:-adaptive}
BACKENDS=${BACKENDS:-workers2 ray}
mkdir -p "$OUT"
$A assets procedural > /dev/null 2>&1 || true   # the built-in library is built once, outside the timing
done_run() { [ -f "$OUT/$1.time" ] && grep -q 'Elapsed (wall' "$OUT/$1.time"; }
case " $BACKENDS " in *" workers2 "*)
  done_run workers2 || /usr/bin/time -v $A generate --out "$OUT/workers2" --num-scenes "$N" --seed 0 --workers 2 \
    --rays "$RAYS" --json > "$OUT/workers2.json" 2> "$OUT/workers2.time" ;;
esac
case " $BACKENDS " in *" ray "*) ;; *)
  echo "workers2: $(grep 'Elapsed (wall' "$OUT/workers2.time" | awk '{print $NF}') wall, $N scenes"; exit 0 ;;
esac
export RAY_USAGE_STATS_ENABLED=0 RAY_AUTH_MODE=disabled
PORT=${PORT:-6391}
TMPD=$(mktemp -d /tmp/rayXXXX)
$RAY start --head --port="$PORT" --include-dashboard=false --temp-dir="$TMPD" --num-cpus=1 \
  --node-ip-address=127.0.0.1 --disable-usage-stats > "$OUT/ray-start.log" 2>&1
trap '$RAY stop --force > /dev/null 2>&1 || true' EXIT
$RAY start --address="127.0.0.1:$PORT" --num-cpus=1 --node-ip-address=127.0.0.1 --disable-usage-stats \
  >> "$OUT/ray-start.log" 2>&1
/usr/bin/time -v $A generate --out "$OUT/ray" --num-scenes "$N" --seed 0 --backend ray \
  --ray-address "127.0.0.1:$PORT" --rays "$RAYS" --json > "$OUT/ray.json" 2> "$OUT/ray.time"
for r in $BACKENDS; do
  echo "$r: $(grep 'Elapsed (wall' "$OUT/$r.time" | awk '{print $NF}') wall, $N scenes"
done
