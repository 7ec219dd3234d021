# The decision of rule-snaprank.md from the output of scripts/hybrid_eval.py on the 17 fixed models:
# per model hybrid vs hybrid+snap_rank AP50 on the dev scans and on scene0451_01, the means and the
# counts of models not lower.
#   python decide.py snaprank17.json
import json
import sys

import numpy as np

d = json.load(open(sys.argv[1]))
rows = []
for name, r in d["models"].items():
    rows.append((name, [g["AP50"] for g in r["hybrid"]], [g["AP50"] for g in r["hybrid+snap_rank"]],
                 [g["AP"] for g in r["hybrid"]], [g["AP"] for g in r["hybrid+snap_rank"]],
                 [g["AP25"] for g in r["hybrid"]], [g["AP25"] for g in r["hybrid+snap_rank"]]))
print("model | hybrid AP50 dev / 0451 | snap_rank AP50 dev / 0451 | AP dev | AP25 dev")
for name, h, s, ha, sa, h25, s25 in rows:
    print(f"{name} | {h[0]:.3f} / {h[1]:.3f} | {s[0]:.3f} / {s[1]:.3f} | {ha[0]:.3f} -> {sa[0]:.3f} | {h25[0]:.3f} -> {s25[0]:.3f}")
ok = True
for g, label in ((0, "dev"), (1, "scene0451_01")):
    h = np.array([r[1][g] for r in rows])
    s = np.array([r[2][g] for r in rows])
    not_lower = int((s >= h).sum())
    print(f"{label}: mean {h.mean():.4f} -> {s.mean():.4f} ({s.mean() - h.mean():+.4f}); higher {int((s > h).sum())}, "
          f"equal {int((s == h).sum())}, lower {int((s < h).sum())}; not lower {not_lower} of {len(rows)}")
    ok &= bool(s.mean() > h.mean() and not_lower >= 13)
print("rule met" if ok else "rule not met")
