"""The plan's reading: learned dev AP50 per seed and arm, per room, and the rule (OUT/ARM/seed_K/result.json);
the hybrid_eval rows (OUT/hybrid-ARM.json) descriptively.   python table.py OUT"""
import json
import statistics
import sys
from pathlib import Path

out = Path(sys.argv[1])
arms = ("float32", "bfloat16")
runs = {a: [json.loads(p.read_text()) for p in sorted((out / a).glob("seed_*/result.json"))] for a in arms}
print("| arm | seeds | learned dev AP50 per seed | mean +- sd | AP25 mean | AP mean | train s per seed |")
print("| --- | ---: | --- | ---: | ---: | ---: | --- |")
for a, rs in runs.items():
    ap50 = [r["AP50"] for r in rs]
    sd = statistics.stdev(ap50) if len(ap50) > 1 else float("nan")
    print(f"| {a} | {len(rs)} | {' / '.join(f'{x:.3f}' for x in ap50)} | {statistics.mean(ap50):.3f} +- {sd:.3f} | "
          f"{statistics.mean(r['AP25'] for r in rs):.3f} | {statistics.mean(r['AP'] for r in rs):.3f} | "
          f"{' / '.join(str(r['train_seconds']) for r in rs)} |")
rooms = sorted({s[:9] for r in runs["float32"] for s in r["per_scene"]})
print("\n| room | " + " | ".join(arms) + " |\n| --- | " + " | ".join("---:" for _ in arms) + " |")
for room in rooms:
    cells = []
    for a in arms:
        vals = [v["AP50"] for r in runs[a] for s, v in r["per_scene"].items() if s[:9] == room]
        cells.append(f"{statistics.mean(vals):.3f}" if vals else "-")
    print(f"| {room} | " + " | ".join(cells) + " |")
f, b = ([r["AP50"] for r in runs[a]] for a in arms)
if len(f) >= 2 and len(b) >= 2:
    margin = max(0.02, statistics.stdev(f), statistics.stdev(b))
    gap = statistics.mean(b) - statistics.mean(f)
    keep = gap >= -margin
    print(f"\nbfloat16 - float32 {gap:+.3f}, margin {margin:.3f}: "
          + ("bfloat16 stays the default (auto)" if keep else "float32 becomes the default") + " by the plan's rule")
else:
    print("\nincomplete: fewer than 2 seeds an arm; nothing concluded")
for a in arms:
    p = out / f"hybrid-{a}.json"
    if p.is_file():
        h = json.loads(p.read_text())
        print(f"\n{a} hybrid_eval: " + json.dumps({k: v for k, v in h.items() if k in ("rows", "summary")})[:1500])
