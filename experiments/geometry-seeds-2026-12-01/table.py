"""Tabulate run.sh: geometry diversity per dataset at metric seeds 0-4, and the orderings of plan.md."""
import json
import sys
from pathlib import Path

import numpy as np

R = Path(sys.argv[1])
rows = {s: [json.loads(line) for line in (R / f"seeds-s{s}.jsonl").read_text().splitlines() if line.strip()]
        for s in (0, 1)}
names = list(rows[0][0])
print("| dataset | " + " | ".join(f"gen. seed {s}: metric seed 0 / mean ± sd over {len(rows[s])}" for s in rows) + " |")
for n in names:
    cells = []
    for s in rows:
        v = np.array([r[n] for r in rows[s]])
        cells.append(f"{v[0]:.3f} / {v.mean():.3f} ± {v.std(ddof=1):.3f}")
    print(f"| {n} | " + " | ".join(cells) + " |")
pairs = [("assist3d", "holodeck-style"), ("randomrooms", "holodeck-style"), ("assist3d", "randomrooms"),
         ("assist3d", "no-context")]
for a, b in pairs:
    diffs = [r[a] - r[b] for s in rows for r in rows[s]]
    above = sum(d > 0 for d in diffs)
    verdict = "holds" if above == len(diffs) else ("reversed at every seed" if above == 0 else "not separated")
    print(f"{a} above {b}: {above} of {len(diffs)} (differences {min(diffs):+.3f} .. {max(diffs):+.3f}): {verdict}")
