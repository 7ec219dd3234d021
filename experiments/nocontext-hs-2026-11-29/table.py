"""Table and reading of plan.md beside this file (context complexity on household-sparse data, 200 steps).

    python experiments/nocontext-hs-2026-11-29/table.py

ASSIST-3D: arm A's three committed seeds (../holodeck-why-2026-11-28/per_seed/). no-context: per_seed/ here.
scene0451_01: s0451-seedK.json here (experiments/tools/noise_robustness.py --sigma 0, today's inference).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ARM_A = HERE.parent / "holodeck-why-2026-11-28" / "per_seed"
ROOMS = ("scene0006", "scene0007", "scene0008", "scene0009", "scene0010")


def load(folder: Path, stem: str) -> list[dict]:
    runs = [json.loads((folder / f"{stem}-seed{k}.json").read_text()) for k in range(3)
            if (folder / f"{stem}-seed{k}.json").exists()]
    if any(r["steps"] != 200 for r in runs):
        raise SystemExit(f"{stem}: a run not trained for 200 steps")
    return runs


def per_room(runs: list[dict]) -> list[float]:
    return [float(np.mean([np.mean([v["AP50"] for s, v in r["per_scene"].items() if s.startswith(room)])
                           for r in runs])) for room in ROOMS]


def reading(a: list[dict], nc: list[dict], lead: str = "context complexity carries part of the lead") -> str:
    """The plan's rule on the learned dev AP50 of paired seeds: ASSIST-3D ahead by more than the larger std."""
    va, vn = np.array([r["AP50"] for r in a]), np.array([r["AP50"] for r in nc])
    gap, sd = va.mean() - vn.mean(), max(va.std(ddof=1), vn.std(ddof=1))
    if gap > sd:
        verdict = lead
    elif gap >= -sd:
        verdict = "no effect of that size"
    else:
        verdict = "no-context above ASSIST-3D by more than one std (reported as it is)"
    return (f"reading: ASSIST-3D - no-context {gap:+.3f} against the larger std {sd:.3f}, ASSIST-3D ahead in "
            f"{int(np.sum(va > vn))} of 3 paired seeds: {verdict}")


def main() -> None:
    a, nc = load(ARM_A, "assist3d-household-sparse"), load(HERE / "per_seed", "no-context-household-sparse")
    print("learned dev AP50 (the probe's figure), household-sparse data, 200 steps")
    for name, runs in (("ASSIST-3D (arm A)", a), ("no-context", nc)):
        v = np.array([r["AP50"] for r in runs])
        sd = v.std(ddof=1) if len(v) > 1 else float("nan")
        print(f"  {name:18s} {len(v)} seed(s): {v.mean():.3f} ± {sd:.3f} (" + ", ".join(f"{x:.3f}" for x in v)
              + f"); AP25 {np.mean([r['AP25'] for r in runs]):.3f}; per room "
              + " ".join(f"{x:.3f}" for x in per_room(runs)))
    if len(nc) < 3:
        print("reading: partial, no verdict")
        return
    print(reading(a, nc))
    hyb = [r["hybrid"]["AP50"] for r in nc if "hybrid" in r]
    if hyb:
        print(f"no-context hybrid dev AP50 (today's inference, plane refit): {np.mean(hyb):.3f} ± "
              f"{np.std(hyb, ddof=1):.3f} (" + ", ".join(f"{x:.3f}" for x in hyb) + ")")
    for method in ("learned", "hybrid"):
        vals = {"dev": [], "scene0451_01": []}
        for p in sorted(HERE.glob("s0451-seed*.json")):
            d = json.loads(p.read_text())
            row = next(r for r in d["rows"] if r["method"] == method and r["sigma"] == 0.0 and not r["denoise"])
            for spec in d["eval"]:
                vals["scene0451_01" if spec.endswith("scannet_scene0451_01.npy") else "dev"].append(row[spec]["AP50"])
        if vals["scene0451_01"]:
            print(f"no-context {method}, clean, today's inference (noise_robustness.py): dev "
                  + ", ".join(f"{x:.3f}" for x in vals["dev"]) + "; scene0451_01 "
                  + ", ".join(f"{x:.3f}" for x in vals["scene0451_01"])
                  + f" (mean {np.mean(vals['scene0451_01']):.3f})")


if __name__ == "__main__":
    main()
