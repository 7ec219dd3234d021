#!/usr/bin/env bash
# generators-hs-821: the remaining seeds, each followed by its six evaluations, with the code frozen at the
# comparison's start (a git worktree at /work/frozen821: `git worktree add --detach /work/frozen821 aee3355`; src identical to the
# plan's commit aee3355) so that development in /work/main cannot reach these runs.
export PYTHONPATH=/work/frozen821/src
cd /work/main; source .venv/bin/activate
S=/work/scratch/s21; DEV=/work/shared/data/real/dev; O=$S/probe821
frozen() { python -c "import assist3d, sys; assert assist3d.__file__.startswith('/work/frozen821/'), assist3d.__file__" || exit 1; }
frozen
while pgrep -f "randomrooms-household-sparse --eval" > /dev/null; do sleep 20; done
echo "rr0 probe ended $(date -u)"
bash experiments/generators-hs-821-2026-11-28/evals821.sh
echo "evals done $(date -u)"
for k in 1 2; do
  for g in mesh-sampled randomrooms; do
    echo "$g seed $k start $(date -u)"
    frozen
    assist3d probe --train assist3d:$S/data/$g-household-sparse --eval array:$DEV --steps 821 --seeds $((k+1)) --threads 2 --loader-workers 0 --out $O/$g-household-sparse --json > $O/$g.json 2> $O/$g-$k.log
    echo "$g seed $k done $(date -u)"
    bash experiments/generators-hs-821-2026-11-28/evals821.sh
    echo "evals done $(date -u)"
  done
done
