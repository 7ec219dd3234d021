"""Reading of plan-eval-spread.md: how much of the probe's seed spread is evaluation noise.

    python experiments/noise-2026-11-28/spread_table.py

Clean figures: the six ASSIST-3D seeds of the generator comparison with today's defaults
(../fidelity-ema-2026-11-27/per_seed/assist3d-seedK.json, learned and hybrid dev AP50; hybrid made without
the plane refit). Noisy: spread/mK-seedS.json beside this file (experiments/tools/noise_robustness.py --model
.../assist3d/seed_K/model.pt --sigma 0.001 --seed S --methods learned hybrid --refine-planes 0, dev scans).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CLEAN = HERE.parent / "fidelity-ema-2026-11-27" / "per_seed"
MODELS, DRAWS = range(6), range(5)


def noisy(k: int, s: int, method: str) -> float:
    d = json.loads((HERE / "spread" / f"m{k}-seed{s}.json").read_text())
    if not d["model"].endswith(f"/assist3d/seed_{k}/model.pt") or d["seed"] != s or len(d["eval"]) != 1:
        raise SystemExit(f"m{k}-seed{s}.json: not model {k}, draw {s} on one eval spec")
    if d.get("refine_planes", 0) not in (0, {"geometric": 0, "hybrid": 0}):
        raise SystemExit(f"m{k}-seed{s}.json: made with the plane refit; the clean figures were made without")
    row = next(r for r in d["rows"] if r["method"] == method and r["sigma"] == 0.001)
    return row[d["eval"][0]]["AP50"]


def main() -> None:
    for method in ("learned", "hybrid"):
        clean = np.array([(lambda r: r if method == "learned" else r["hybrid"])(
            json.loads((CLEAN / f"assist3d-seed{k}.json").read_text()))["AP50"] for k in MODELS])
        draws = np.array([[noisy(k, s, method) for s in DRAWS] for k in MODELS])  # (models, draws)
        means = draws.mean(1)
        within = np.sqrt(draws.var(1, ddof=1).mean())  # pooled within-model sd over draws
        print(f"{method}: per model clean / 5-draw mean (draws):")
        for k in MODELS:
            print(f"  seed {k}: {clean[k]:.3f} / {means[k]:.3f} (" + " ".join(f"{x:.3f}" for x in draws[k]) + ")")
        sd_clean, sd_mean = clean.std(ddof=1), means.std(ddof=1)
        share = min(1.0, within ** 2 / sd_clean ** 2)
        print(f"  sd over the 6 models: clean {sd_clean:.3f}, 5-draw mean {sd_mean:.3f}; pooled within-model sd "
              f"over draws {within:.3f}; draw variance / clean seed variance {within ** 2 / sd_clean ** 2:.2f} "
              f"(share, capped at 1: {share:.2f})")
        if method == "learned":
            verdict = ("scoring over noise draws would help the probe (next step: an option)"
                       if sd_mean < sd_clean / 2 else "reported as it is (the 5-draw mean does not halve the spread)")
            print(f"  reading (plan-eval-spread.md): {sd_mean:.3f} vs half of {sd_clean:.3f}: {verdict}")


if __name__ == "__main__":
    main()
