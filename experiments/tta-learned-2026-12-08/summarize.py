"""plan.md's reading of run.py's JSON files: per room AP50 with and without TTA, the paired comparison, the seconds,
and the rule's verdict.

    PYTHONPATH=src python experiments/tta-learned-2026-12-08/summarize.py SHIPPED.json [CHECK.json]
"""

from __future__ import annotations

import json
import statistics
import sys
from pathlib import Path

from assist3d.bench.evaluation.compare import paired_comparison, room_means

PLAIN, TTA = "learned-timed", "learned-tta"
BOUND_S = 15.0
SCAN_0451 = "scannet_scene0451_01"


def read(path: Path) -> dict:
    res = json.loads(path.read_text())
    out = {}
    for metric in ("AP50", "AP", "AP25"):
        a = room_means({s: f[metric] for s, f in res[PLAIN]["per_scene"].items()})
        b = room_means({s: f[metric] for s, f in res[TTA]["per_scene"].items()})
        out[metric] = (a, b, paired_comparison(a, b, metric=metric))
    out["seconds"] = {k: (res[k]["predict_seconds"], res[k]["network_seconds"].get(SCAN_0451)) for k in (PLAIN, TTA)}
    return out


def main() -> None:
    shipped = read(Path(sys.argv[1]))
    check = read(Path(sys.argv[2])) if len(sys.argv) > 2 else None
    for name, r in (("shipped", shipped), ("check", check)):
        if r is None:
            continue
        for metric in ("AP50", "AP", "AP25"):
            a, b, c = r[metric]
            print(f"{name} {metric}: 6-room mean {statistics.mean(a.values()):.3f} -> {statistics.mean(b.values()):.3f} "
                  f"({c.mean_diff:+.3f}, interval over rooms [{c.ci95[0]:+.3f}, {c.ci95[1]:+.3f}], higher in {c.higher}, "
                  f"lower in {c.lower} of {c.scans} rooms)")
            if metric == "AP50":
                print("  per room: " + ", ".join(f"{k} {a[k]:.3f}->{b[k]:.3f}" for k in a))
        (p_all, p_0451), (t_all, t_0451) = r["seconds"][PLAIN], r["seconds"][TTA]
        print(f"{name} seconds, all 11 scans: {p_all} -> {t_all}; {SCAN_0451}: {p_0451} -> {t_0451}")
    _, _, c = shipped["AP50"]
    ok1 = c.mean_diff > 0 and c.ci95[0] > 0 and c.higher >= 5
    ok2 = None if check is None else check["AP50"][2].mean_diff >= 0
    t_0451 = shipped["seconds"][TTA][1]
    ok3 = t_0451 is not None and t_0451 < BOUND_S
    print(f"rule: 1 (shipped higher, interval above 0, >= 5 of 6 rooms) {ok1}; 2 (check not lower) "
          f"{'not measured' if ok2 is None else ok2}; 3 (scene0451_01 under {BOUND_S:.0f} s with TTA) {ok3}")
    if ok1 and ok2 and ok3:
        print("verdict: adopt (segment runs with TTA by default)")
    elif not (ok1 and ok3) or ok2 is False:
        print("verdict: not adopted; --tta stays opt-in")
    else:
        print("verdict: the check model is still to measure")


if __name__ == "__main__":
    main()
