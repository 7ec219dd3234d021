"""Reading of plan-eval-spread.md's amendment: evaluation noise against seed spread, nine models.

    python experiments/noise-2026-11-28/spread2_table.py

Files: spread2/GEN-K-clean.json and spread2/GEN-K-seedS.json beside this file (spread2.sh:
experiments/tools/noise_robustness.py, household-sparse 200-step model K of generator GEN, dev scans, hybrid without the
plane refit). Beside it, not part of the reading: the ship candidate's three 821-step seeds (its six
evaluations each, with the plane refit, dev scans).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
FILES = HERE / "spread2"
GENS = ("assist3d", "mesh-sampled", "randomrooms")
SEEDS, DRAWS = range(3), range(5)
CAND = HERE.parent / "ship-candidate-2026-11-28"
sys.path.insert(0, str(CAND))
from rule import figures  # noqa: E402  (the candidate's evaluation files, checked as its rule reads them)
from noise_robustness import plane_refits  # noqa: E402  (rule.py put scripts/ on the path)


def ap50(name: str, method: str, sigma: float, seed: int | None) -> float:
    path = FILES / name
    d = json.loads(path.read_text())
    if len(d["eval"]) != 1 or not d["eval"][0].endswith("/dev"):
        raise SystemExit(f"{path}: not one evaluation on the dev scans")
    if plane_refits(d) != {"geometric": 0, "hybrid": 0}:
        raise SystemExit(f"{path}: made with the plane refit; the amendment fixes hybrid without it")
    if seed is not None and d.get("seed") != seed:
        raise SystemExit(f"{path}: noise seed {d.get('seed')}, not {seed}")
    row = next(r for r in d["rows"] if r["method"] == method and r["sigma"] == sigma and not r["denoise"])
    return row[d["eval"][0]]["AP50"]


def pooled(groups: np.ndarray) -> float:
    """Root of the mean over groups of the within-group variance (axis 1 within a group)."""
    return float(np.sqrt(groups.var(axis=-1, ddof=1).mean()))


def spreads(clean: np.ndarray, draws: np.ndarray) -> tuple[float, float, float]:
    """clean (groups, seeds), draws (groups, seeds, draws): pooled seed sd of clean and of the draw mean,
    pooled within-model sd over draws."""
    return pooled(clean), pooled(draws.mean(-1)), pooled(draws.reshape(-1, draws.shape[-1]))


def main() -> None:
    for method in ("learned", "hybrid"):
        clean = np.array([[ap50(f"{g}-{k}-clean.json", method, 0.0, None) for k in SEEDS] for g in GENS])
        draws = np.array([[[ap50(f"{g}-{k}-seed{s}.json", method, 0.001, s) for s in DRAWS] for k in SEEDS]
                          for g in GENS])
        means = draws.mean(-1)
        print(f"{method} dev AP50 (hybrid without the plane refit): per model clean / 5-draw mean (draws)")
        for i, g in enumerate(GENS):
            for k in SEEDS:
                print(f"  {g:13s} seed {k}: {clean[i, k]:.3f} / {means[i, k]:.3f} ("
                      + " ".join(f"{x:.3f}" for x in draws[i, k]) + ")")
            print(f"  {g:13s} mean: clean {clean[i].mean():.3f} ± {clean[i].std(ddof=1):.3f}, "
                  f"5-draw mean {means[i].mean():.3f} ± {means[i].std(ddof=1):.3f}")
        sd_a, sd_b, within = spreads(clean, draws)
        print(f"  pooled seed sd (3 generators x 3 seeds, 6 df): (a) clean {sd_a:.3f}, (b) 5-draw mean {sd_b:.3f}; "
              f"pooled within-model sd over draws {within:.3f}; draw variance / (a)'s variance "
              f"{within ** 2 / sd_a ** 2:.2f} (share, capped at 1: {min(1.0, within ** 2 / sd_a ** 2):.2f})")
        for j in (1, 2):
            gc, gm = clean[0].mean() - clean[j].mean(), means[0].mean() - means[j].mean()
            print(f"  ASSIST-3D minus {GENS[j]}: clean {gc:+.3f} ({gc / sd_a:+.1f} seed sd), "
                  f"5-draw mean {gm:+.3f} ({gm / sd_b:+.1f} seed sd)")
        if method == "learned":
            verdict = ("scoring over noise draws would help the probe (next step: an option)" if sd_b < sd_a / 2
                       else "reported as it is (the 5-draw mean does not halve the seed spread)")
            print(f"  reading (plan-eval-spread.md, amendment): (b) {sd_b:.3f} vs half of (a) {sd_a / 2:.3f}: {verdict}")
    print("beside it: the ship candidate's 821-step seeds 0-2, dev, with the plane refit")
    folders = [CAND, CAND / "seed1", CAND / "seed2"]
    for method in ("learned", "hybrid"):
        f = np.array([figures(p, method)["dev"] for p in folders])  # (seeds, clean + 5 draws)
        clean, draws = f[None, :, 0], f[None, :, 1:]
        sd_a, sd_b, within = spreads(clean, draws)
        print(f"  {method}: clean " + " ".join(f"{x:.3f}" for x in clean[0]) + ", 5-draw means "
              + " ".join(f"{x:.3f}" for x in draws[0].mean(-1)) + f"; seed sd clean {sd_a:.3f}, 5-draw mean "
              f"{sd_b:.3f}; within-model sd over draws {within:.3f}")


if __name__ == "__main__":
    main()
