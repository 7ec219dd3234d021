#!/usr/bin/env bash
# The rest of plan.md in one command, for a session on an AMX Xeon (bfloat16): the 250 scenes (if absent), seed 1
# of the 4.5 m crop, the bench check, the decision, and, only if the crop is adopted, the scaling study's
# 8,210-step point with it (about 150 minutes in all on that VM; each piece resumes when re-run).
#   experiments/crop-2026-12-07/next_session.sh OUT       (from the repository root; ASSIST3D, DEV, EXTRA as run.sh)
# Afterwards: summarize.py --copy OUT; scaling-2026-12-05/summarize.py --copy OUT/crop45 is NOT to be mixed
# with the 6 m points (its folder is separate on purpose): report it as the named deviation.
set -euo pipefail
OUT=${1:?usage: next_session.sh OUT}
A=${ASSIST3D:-assist3d}
PY=${PYTHON:-python3}
HERE=experiments/crop-2026-12-07
mkdir -p "$OUT"
date -u; echo "data"
$A generate --out "$OUT/data" --num-scenes 250 --seed 0 --preset assist3d --workers 2 --rays full --json \
  > "$OUT/generate-250.json" 2> "$OUT/generate-250.log"
date -u; echo "crop seed 1"
$HERE/run.sh "$OUT" "$OUT/data" 1
$PY $HERE/summarize.py --copy "$OUT" | tee "$OUT/summary.txt"
date -u; echo "bench check, three pairs"
mkdir -p "$OUT/bench"
for k in 0 1 2; do
  $A bench-train --data "assist3d:$OUT/data" --steps 20 --json > "$OUT/bench/c60-$k.json" 2>/dev/null
  $A bench-train --data "assist3d:$OUT/data" --steps 20 --config $HERE/crop45.yaml --json > "$OUT/bench/c45-$k.json" 2>/dev/null
done
if $PY - "$OUT/bench" <<'PY'
import json, sys
from pathlib import Path
d = Path(sys.argv[1])
pairs = [(json.loads((d / f"c60-{k}.json").read_text())["step_s_median"],
          json.loads((d / f"c45-{k}.json").read_text())["step_s_median"]) for k in range(3)]
ratios = [a / b for a, b in pairs]
print("bench 6 m / 4.5 m s a step:", ", ".join(f"{a:.3f}/{b:.3f} = {r:.2f}x" for (a, b), r in zip(pairs, ratios)))
sys.exit(0 if all(r >= 1.3 for r in ratios) else 1)
PY
then bench_ok=1; else bench_ok=0; fi
if [ "$bench_ok" = 1 ] && $PY $HERE/summarize.py --decide > /dev/null; then
  date -u; echo "ADOPTED by plan.md: the 8,210-step point with the 4.5 m crop"
  CONFIG=$HERE/crop45.yaml SEEDS=0 DATA="$OUT/data" experiments/scaling-2026-12-05/run.sh "$OUT/crop45" "8210:250"
else
  date -u; echo "NOT adopted (bench ok: $bench_ok): 6 m stays; run the scaling study's remaining points instead"
fi
date -u; echo DONE
