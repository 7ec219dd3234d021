"""The two arms' learned dev AP50 per seed, mean +- sd, and the plan's one-pooled-sd rule (per_seed/*.json)."""
import json
import statistics
import sys
from pathlib import Path

here = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent)
arms = {}
for arm in ("guided", "random"):
    runs = sorted(here.glob(f"per_seed/{arm}-seed*.json"))
    arms[arm] = [json.loads(p.read_text()) for p in runs]
print("| arm | seeds | learned dev AP50 per seed | mean +- sd | AP25 mean | AP mean |")
print("| --- | ---: | --- | ---: | ---: | ---: |")
for arm, rs in arms.items():
    ap50 = [r["AP50"] for r in rs]
    sd = statistics.stdev(ap50) if len(ap50) > 1 else float("nan")
    print(f"| {arm} | {len(rs)} | {' / '.join(f'{x:.3f}' for x in ap50)} | {statistics.mean(ap50):.3f} +- {sd:.3f} | "
          f"{statistics.mean(r['AP25'] for r in rs):.3f} | {statistics.mean(r['AP'] for r in rs):.3f} |")
g, r = ([x["AP50"] for x in arms[a]] for a in ("guided", "random"))
if len(g) >= 2 and len(r) >= 2:
    pooled = ((statistics.variance(g) * (len(g) - 1) + statistics.variance(r) * (len(r) - 1)) / (len(g) + len(r) - 2)) ** 0.5
    gap = statistics.mean(g) - statistics.mean(r)
    verdict = "guided ahead" if gap > pooled else "random ahead" if -gap > pooled else "not separated"
    print(f"\ngap guided - random {gap:+.3f}, pooled sd {pooled:.3f}: {verdict} by the plan's rule"
          + ("" if len(g) >= 3 and len(r) >= 3 else " (incomplete: fewer than 3 seeds an arm)"))
