#!/usr/bin/env bash
# issue 14's acceptance on a clean clone beside the project (../shared resolves as in CI), on the final code of the
# session of 2026-11-29 05:23 UTC (as experiments/issue14-acceptance-2026-11-29b/run.sh, plus: the hostile endpoint
# of deliverable 2, the second preset draw of experiments/realism-draws-2026-11-29 (P1), layout_realism_se).
# Datasets: the presets of experiments/realism-presets-2026-11-29/run.sh (P), the household sets of
# experiments/realism-objects-2026-11-29/run-household.sh (H), the Sweet Home 3D catalog
# (`assist3d assets import sh3d --library S`) and the combo catalog (C).
set -u
A=${A:?output folder}; P=${P:?preset datasets}; P1=${P1:?seed-1 preset datasets}; H=${H:?household datasets}; S=${S:?Sweet Home 3D catalog}
C=${C:?Sweet Home 3D + procedural catalog}; mkdir -p $A
cd /work/main && rm -rf ../ci-check && git clone -q . ../ci-check && cd ../ci-check
git log --oneline -1
date -u; echo "== .ci/run"
( time bash .ci/run ) > $A/ci.log 2>&1; echo "ci rc $?"; grep -E "passed|failed" $A/ci.log | tail -1
source .venv/bin/activate
date -u; echo "== acceptance 1: assist3d layout against a 2 s fake endpoint"
bash experiments/llm-batch-2026-11-29/cli_check.sh $C $A/cli 2>&1
for m in serial concurrent batched batched-cache; do tail -1 $A/cli/$m.err; done
date -u; echo "== deliverable 2: the hostile endpoint (2 s, every 6th request stalls 45 s), must finish in < 150 s"
python scripts/bench_llm_planning.py --assets $C --latency 2 --stall-every 6 --stall-s 45 --modes concurrent,batched \
  --json > $A/hostile.json 2> $A/hostile.err; echo "hostile rc $?"
python -c "import json;r=json.load(open('$A/hostile.json'));print(json.dumps(r)[:1500])"
date -u; echo "== acceptance 3: 50 layouts on the Sweet Home 3D catalog, check_layout"
python scripts/layout_stats.py --assets $S --scenes 50 > $A/layout_stats.json
python -c "import json;r=json.load(open('$A/layout_stats.json'));print({k:r[k] for k in ('assets','scenes','mean_placed','check_problems_total','scenes_with_problems')})"
date -u; echo "== acceptance 2: layout realism, 50-scene sets, through assist3d metrics (shipped reference)"
assist3d metrics assist3d:$P/assist3d assist3d:$P/randomrooms assist3d:$P/holodeck-style assist3d:$P1/assist3d \
  assist3d:$P1/randomrooms assist3d:$P1/holodeck-style array:../shared/data/real/dev \
  --assets $C --json > $A/metrics.json 2> $A/metrics.err
python -c "import json;r=json.load(open('$A/metrics.json'));[print(k, v['layout_realism'], '+-', v['layout_realism_se'], v['layout_realism_reference']) for k,v in r.items()]"
date -u; echo "== the same and the household sets, with real rooms at equal size (--loro --matched 200)"
python scripts/realism_reference.py array:../shared/data/real/dev --loro --score assist3d:$P/assist3d assist3d:$P/randomrooms \
  assist3d:$P/holodeck-style assist3d:$H/assist3d-hs assist3d:$H/randomrooms-hs assist3d:$H/holodeck-allmodels \
  --max-scenes 50 --matched 200 --json > $A/matched.json 2> $A/matched.err
echo "matched rc $?"
python - $A/matched.json <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print("real rooms:", {k: v["layout_realism"] for k, v in r["loro"].items()}, "mean", r["loro_mean"])
for spec, v in r["scores"].items():
    print(spec.split("/")[-1], v["layout_realism"], "at equal size", r["matched"]["datasets"][spec]["mean"])
PY
date -u; echo ALLDONE
