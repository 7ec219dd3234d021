"""Learned and hybrid AP50 of the six models (hyb-*.json from scripts/hybrid_eval.py): dev and scene0451_01."""
import json
import statistics
from pathlib import Path

here = Path(__file__).parent
print("| arm | row | dev AP50 per seed | dev mean +- sd | scene0451_01 per seed | scene0451_01 mean |")
print("| --- | --- | --- | ---: | --- | ---: |")
for arm in ("guided", "random"):
    models = json.loads((here / f"hyb-{arm}.json").read_text())["models"]
    for row in ("learned", "hybrid"):
        dev = [m[row][0]["AP50"] for m in models.values()]
        s0451 = [m[row][1]["AP50"] for m in models.values()]
        print(f"| {arm} | {row} | {' / '.join(f'{x:.3f}' for x in dev)} | {statistics.mean(dev):.3f} +- "
              f"{statistics.stdev(dev):.3f} | {' / '.join(f'{x:.3f}' for x in s0451)} | {statistics.mean(s0451):.3f} |")
