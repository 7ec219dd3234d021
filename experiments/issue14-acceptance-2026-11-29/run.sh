#!/usr/bin/env bash
# (2026-11-29 later: '?objects=benchmark' pins the reading these figures were made with; the realism code now reads
# real scans with every annotated object unless told so: experiments/realism-objects-2026-11-29)
# issue 14's acceptance on a clean clone beside the project (../shared resolves as in CI)
set -u
A=/work/scratch/s25/acc
cd /work/main && rm -rf ../ci-check && git clone -q . ../ci-check && cd ../ci-check
git log --oneline -1
date -u; echo "== .ci/run"
( time bash .ci/run ) > $A/ci.log 2>&1; echo "ci rc $?"; grep -E "passed|failed" $A/ci.log | tail -1
source .venv/bin/activate
date -u; echo "== acceptance 1: assist3d layout against a 2 s fake endpoint"
bash experiments/llm-batch-2026-11-29/cli_check.sh /work/scratch/combo-lib $A/cli 2>&1
for m in serial concurrent batched batched-cache; do tail -1 $A/cli/$m.err; done
date -u; echo "== acceptance 3: 50 layouts on the Sweet Home 3D catalog, check_layout"
python scripts/layout_stats.py --assets /work/scratch/s25/sh3d-lib --scenes 50 > $A/layout_stats.json
python -c "import json;r=json.load(open('$A/layout_stats.json'));print({k:r[k] for k in ('assets','scenes','mean_placed','check_problems_total','scenes_with_problems')})"
date -u; echo "== acceptance 2: layout realism, 50-scene sets"
P=/work/scratch/s25/realism
python scripts/realism_reference.py 'array:../shared/data/real/dev?objects=benchmark' --score assist3d:$P/assist3d assist3d:$P/randomrooms assist3d:$P/holodeck-style \
  assist3d:/work/scratch/s20/data/assist3d-household-sparse assist3d:/work/scratch/s20/data/holodeck-allmodels \
  assist3d:/work/scratch/s21/data/randomrooms-household-sparse --max-scenes 50 2> $A/realism.err
date -u; echo "== real rooms at equal size (--loro --matched 200)"
python scripts/realism_reference.py 'array:../shared/data/real/dev?objects=benchmark' --loro --score assist3d:$P/assist3d assist3d:$P/randomrooms assist3d:$P/holodeck-style \
  assist3d:/work/scratch/s20/data/assist3d-household-sparse assist3d:/work/scratch/s20/data/holodeck-allmodels \
  assist3d:/work/scratch/s21/data/randomrooms-household-sparse --max-scenes 50 --matched 200 --json > $A/matched.json 2> $A/matched.err
echo "matched rc $?"
date -u; echo ALLDONE
