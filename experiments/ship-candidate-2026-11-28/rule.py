"""The adoption rule of plan.md beside this file, applied to the candidate's evaluation files.

    python experiments/ship-candidate-2026-11-28/rule.py [FOLDER]

FOLDER (default: this folder, the candidate, seed 0) holds another model's six files in the same
names, e.g. seed1/ for the second seed, which the plan reports without a decision of its own.

Candidate: r2-clean.json and r2-1mm-seed0..4.json beside this file (experiments/tools/noise_robustness.py with the
candidate's model, today's inference, dev scans and scene0451_01). Shipped model: the same files in
../noise-2026-11-28/refine/. S = mean hybrid AP50 over the six evaluations, per evaluation set.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "scripts"))
from noise_robustness import plane_refits  # noqa: E402  (how that script's files record the refits)
SHIPPED = HERE.parent / "noise-2026-11-28" / "refine"
NAMES = ["r2-clean.json"] + [f"r2-1mm-seed{s}.json" for s in range(5)]
SETS = ("dev", "scannet_scene0451_01.npy")


# The shipped model's S as plan.md fixed them (4 decimals), checked against its files below.
PLAN_DEV, PLAN_S0451 = 0.2447, 0.1220


def figures(folder: Path, method: str) -> dict[str, list[float]]:
    """Per evaluation set, AP50 of ``method`` over the six evaluations (clean first)."""
    out: dict[str, list[float]] = {k: [] for k in SETS}
    for name in NAMES:
        d = json.loads((folder / name).read_text())
        if name != "r2-clean.json" and d.get("seed") != int(name.removesuffix(".json")[-1]):
            raise SystemExit(f"{folder / name}: noise seed {d.get('seed')}, not the one its name says")
        if folder != SHIPPED and d["model"].endswith("segmenter-v1.pt"):
            raise SystemExit(f"{folder / name}: made with the shipped model, not the candidate")
        if plane_refits(d).get("hybrid") != 2:
            raise SystemExit(f"{folder / name}: not made with today's hybrid inference (plane refit 2)")
        sigma = 0.0 if name == "r2-clean.json" else 0.001
        row = next(r for r in d["rows"] if r["method"] == method and r["sigma"] == sigma and not r["denoise"])
        for spec in d["eval"]:
            key = next(k for k in SETS if spec.endswith(k))
            out[key].append(row[spec]["AP50"])
    if any(len(v) != len(NAMES) for v in out.values()):
        raise SystemExit(f"{folder}: expected both evaluation sets in every file")
    return out


def main() -> None:
    folder = Path(sys.argv[1]).resolve() if len(sys.argv) > 1 else HERE
    got = {}
    for method in ("hybrid", "learned"):
        got[method] = cand, ship = figures(folder, method), figures(SHIPPED, method)
        print(f"{method} AP50 (clean / 1 mm draws 0-4 -> S, the mean of the six):")
        for key in SETS:
            for who, f in (("candidate", cand), ("shipped", ship)):
                draws = np.array(f[key][1:])
                print(f"  {key:26s} {who:9s} {f[key][0]:.3f} / " + " ".join(f"{x:.3f}" for x in draws)
                      + f" -> S {np.mean(f[key]):.4f} (draws {draws.mean():.3f} ± {draws.std(ddof=1):.3f})")
    cand, ship = got["hybrid"]
    if (round(float(np.mean(ship["dev"])), 4), round(float(np.mean(ship[SETS[1]])), 4)) != (PLAN_DEV, PLAN_S0451):
        raise SystemExit("the shipped model's files no longer give the S values plan.md fixed")
    c_dev, s_dev = float(np.mean(cand["dev"])), PLAN_DEV
    c_451, s_451 = float(np.mean(cand[SETS[1]])), PLAN_S0451
    r1, r2 = c_dev > s_dev, c_451 >= s_451
    print(f"rule 1, dev S above the shipped model's: {c_dev:.4f} vs {s_dev:.4f}: {'holds' if r1 else 'fails'}")
    print(f"rule 2, scene0451_01 S not below: {c_451:.4f} vs {s_451:.4f}: {'holds' if r2 else 'fails'}")
    print("rule 3 (size, test_hybrid.py) is checked on the shipped file" if r1 and r2 else
          "verdict: the shipped model stays")


if __name__ == "__main__":
    main()
