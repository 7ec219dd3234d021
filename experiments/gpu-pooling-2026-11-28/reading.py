"""plan.md's reading: GPU-trained seeds of the ship-candidate recipe against its CPU-trained seeds, clean
dev AP50 (learned, hybrid), plus scannet_scene0451_01 (reported, not read). Run from the repo root or here."""
import json
from pathlib import Path

import numpy as np
from scipy import stats

HERE = Path(__file__).resolve().parent
RES = HERE.parent
DEV, S0451 = "array:/work/shared/data/real/dev", "array:/work/shared/data/real/scannet_scene0451_01.npy"
CPU = [RES / "ship-candidate-2026-11-28/r2-clean.json", RES / "ship-candidate-2026-11-28/seed1/r2-clean.json",
       RES / "ship-candidate-2026-11-28/seed2/r2-clean.json"]
GPU = [RES / "gpu-probe-2026-11-28/seed0-821/r2-clean.json"] + [HERE / f"seed{s}/r2-clean.json" for s in range(1, 8)]


def figures(path: Path) -> dict:
    rows = json.loads(path.read_text())["rows"]
    out = {}
    for r in rows:
        if r["sigma"] == 0:
            out[(r["method"], "dev")] = r[DEV]["AP50"]
            out[(r["method"], "s0451")] = r[S0451]["AP50"]
    return out


def reading(cpu: list[float], gpu: list[float]) -> tuple[float, float, float, bool]:
    c, g = np.array(cpu), np.array(gpu)
    df = len(c) + len(g) - 2
    sp = np.sqrt(((len(c) - 1) * c.var(ddof=1) + (len(g) - 1) * g.var(ddof=1)) / df)
    se = sp * np.sqrt(1 / len(g) + 1 / len(c))
    t = stats.t.ppf(0.975, df)
    d = g.mean() - c.mean()
    return d, se, t * se, abs(d) < t * se


cpu = [figures(p) for p in CPU]
gpu = [figures(p) for p in GPU if p.is_file()]
print(f"CPU seeds 0-2, GPU seeds 0-{len(gpu) - 1} (clean AP50)")
for m in ("learned", "hybrid"):
    for where in ("dev", "s0451"):
        c = [f[(m, where)] for f in cpu]
        g = [f[(m, where)] for f in gpu]
        print(f"{m:8s} {where:6s} CPU {' '.join(f'{x:.3f}' for x in c)}  mean {np.mean(c):.3f} sd {np.std(c, ddof=1):.3f}"
              f" | GPU {' '.join(f'{x:.3f}' for x in g)}  mean {np.mean(g):.3f} sd {np.std(g, ddof=1):.3f}")
        if where == "dev":
            print(f"{'':15s} paired GPU-CPU seeds 0-2: {' '.join(f'{g[k] - c[k]:+.3f}' for k in range(3))}")
print()
for label, n in (("fixed reading, GPU seeds 0-4", 5), ("amendment, GPU seeds 0-7", 8)):
    if len(gpu) < n:
        print(f"{label}: only {len(gpu)} GPU seeds scored")
        continue
    verdicts = []
    for m in ("learned", "hybrid"):
        d, se, lim, ok = reading([f[(m, "dev")] for f in cpu], [f[(m, "dev")] for f in gpu[:n]])
        verdicts.append(ok)
        print(f"{label}: {m:7s} dev d = {d:+.3f}, se {se:.3f}, detectable |d| >= {lim:.3f}: "
              f"{'no detectable difference' if ok else 'GPU seeds differ'}")
    print(f"{label}: {'NO DETECTABLE DIFFERENCE on both' if all(verdicts) else 'GPU SEEDS DIFFER'}")
