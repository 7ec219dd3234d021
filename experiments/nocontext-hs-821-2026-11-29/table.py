"""Table and reading of plan.md beside this file (context complexity on household-sparse data, 821 steps).

    python experiments/nocontext-hs-821-2026-11-29/table.py

ASSIST-3D: the ship candidate's three seeds (../ship-candidate-2026-11-28/result.json, seed1/, seed2/), the
plan's fixed reference. no-context: per_seed/ here (each a probe seed's result.json). Six evaluations per
model (clean + five 1 mm draws, learned and hybrid, experiments/tools/noise_robustness.py): eval/no-context-K/ here,
ASSIST-3D's the candidate's. Fewer than three no-context seeds: partial, no verdict.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CAND = HERE.parent / "ship-candidate-2026-11-28"
sys.path.insert(0, str(CAND))
sys.path.insert(0, str(HERE.parent / "nocontext-hs-2026-11-29"))
from rule import figures  # noqa: E402  (the six evaluation files of one model, read as the candidate's rule reads them)
from table import reading  # noqa: E402  (the 200-step plan's rule, the same at 821 steps)

CAND_DIRS = [CAND, CAND / "seed1", CAND / "seed2"]
ROOMS = ("scene0006", "scene0007", "scene0008", "scene0009", "scene0010")


def per_room(runs: list[dict]) -> list[float]:
    return [float(np.mean([np.mean([v["AP50"] for s, v in r["per_scene"].items() if s.startswith(room)])
                           for r in runs])) for room in ROOMS]


def main() -> None:
    a = [json.loads((d / "result.json").read_text()) for d in CAND_DIRS]
    nc = sorted((json.loads(p.read_text()) for p in (HERE / "per_seed").glob("no-context-household-sparse-seed*.json")),
                key=lambda r: r["seed"])
    if any(r["steps"] != 821 for r in a + nc):
        raise SystemExit("a run not trained for 821 steps")
    print("learned dev AP50 (the probe's figure), household-sparse data, 821 steps")
    for name, runs in (("ASSIST-3D", a), ("no-context", nc)):
        v = np.array([r["AP50"] for r in runs])
        sd = f" ± {v.std(ddof=1):.3f}" if len(v) > 1 else ""
        print(f"  {name:10s} {len(v)} seed(s): {v.mean():.3f}{sd} (" + ", ".join(f"{x:.3f}" for x in v)
              + f"); AP25 {np.mean([r['AP25'] for r in runs]):.3f}; per room (0006-0010) "
              + " ".join(f"{x:.3f}" for x in per_room(runs)))
    if len(nc) == 3:
        print(reading(a, nc, "context complexity carries part of the lead at 821 steps"))
    else:
        print(f"reading: partial ({len(nc)} of 3 seeds), no verdict")
    print("six evaluations per model (clean + five 1 mm draws, today's inference), AP50")
    dirs = {"ASSIST-3D": CAND_DIRS,
            "no-context": [d for d in (HERE / "eval" / f"no-context-{k}" for k in range(3))
                           if len(list(d.glob("r2-*.json"))) == 6]}
    summary = {}
    for name, ds in dirs.items():
        figs = [{m: figures(d, m) for m in ("learned", "hybrid")} for d in ds]
        for i, f in enumerate(figs):
            print(f"  {name:10s} seed {i}: " + "   ".join(
                f"{m} dev clean {f[m]['dev'][0]:.3f}, draws {np.mean(f[m]['dev'][1:]):.3f}; scene0451_01 clean "
                f"{f[m]['scannet_scene0451_01.npy'][0]:.3f}, draws {np.mean(f[m]['scannet_scene0451_01.npy'][1:]):.3f}"
                for m in f))
        for m in ("learned", "hybrid"):
            for where in ("dev", "scannet_scene0451_01.npy"):
                clean = np.array([f[m][where][0] for f in figs])
                summary[(name, m, where)] = clean
    for m in ("learned", "hybrid"):
        for where, label in (("dev", "dev"), ("scannet_scene0451_01.npy", "scene0451_01")):
            cells = []
            for name in dirs:
                v = summary[(name, m, where)]
                cells.append(f"{name} {v.mean():.3f}" + (f" ± {v.std(ddof=1):.3f}" if len(v) > 1 else "")
                             + f" ({len(v)})")
            print(f"  {m:7s} clean, {label:12s}: " + ";  ".join(cells))


if __name__ == "__main__":
    main()
