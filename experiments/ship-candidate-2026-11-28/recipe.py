"""The plan amendment's readings over the candidate recipe's three seeds (plan.md beside this file).

    python experiments/ship-candidate-2026-11-28/recipe.py

Seed 0: the files beside this file; seeds 1 and 2: seed1/ and seed2/ (each six evaluations of
experiments/tools/noise_robustness.py, today's inference, dev scans and scene0451_01; read by rule.py's
``figures``). S = the mean AP50 over the six evaluations, per evaluation set.
"""

from __future__ import annotations

import numpy as np

from rule import HERE, PLAN_DEV, PLAN_S0451, SETS, figures

FOLDERS = [HERE, HERE / "seed1", HERE / "seed2"]


def s_values(folder, method: str) -> list[float]:
    """S per evaluation set (SETS order) of one model's six evaluations."""
    fig = figures(folder, method)
    return [float(np.mean(fig[k])) for k in SETS]


def main() -> None:
    s = {m: np.array([s_values(f, m) for f in FOLDERS]) for m in ("learned", "hybrid")}
    print("S per seed (dev / scene0451_01):")
    for i in range(len(FOLDERS)):
        print(f"  seed {i}: learned {s['learned'][i, 0]:.4f} / {s['learned'][i, 1]:.4f}   "
              f"hybrid {s['hybrid'][i, 0]:.4f} / {s['hybrid'][i, 1]:.4f}")
    for m in ("learned", "hybrid"):
        mean, sd = s[m].mean(0), s[m].std(0, ddof=1)
        print(f"  mean over 3 seeds, {m}: dev {mean[0]:.4f} ± {sd[0]:.4f}, scene0451_01 {mean[1]:.4f} ± {sd[1]:.4f}")
    dev, s451 = s["hybrid"].mean(0)
    ok1, ok2 = dev > PLAN_DEV, s451 >= PLAN_S0451
    print(f"recipe, condition 1 (3-seed mean hybrid dev S > {PLAN_DEV}): {dev:.4f}: {'holds' if ok1 else 'fails'}")
    print(f"recipe, condition 2 (3-seed mean hybrid scene0451_01 S >= {PLAN_S0451}): {s451:.4f}: "
          f"{'holds' if ok2 else 'fails'}")
    print("verdict: the recipe passes; its seed 0 (the plan's candidate) goes to rule 3" if ok1 and ok2
          else "verdict: the recipe does not pass; the shipped model stays")
    for j, key in enumerate(SETS):
        above = int(np.sum(s["learned"][:, j] > s["hybrid"][:, j]))
        lm, hm = s["learned"][:, j].mean(), s["hybrid"][:, j].mean()
        if j == 0:
            lowers = lm > hm and above >= 2
            reading = ("hybrid lowers this recipe's networks on the dev scans" if lowers
                       else "hybrid does not lower them (by the amendment's reading)")
            print(f"learned vs hybrid, dev: mean learned S {lm:.4f} vs hybrid {hm:.4f}, "
                  f"learned above in {above} of 3 seeds: {reading}")
        else:
            print(f"learned vs hybrid, {key} (reported): mean learned S {lm:.4f} vs hybrid {hm:.4f}, "
                  f"learned above in {above} of 3 seeds")


if __name__ == "__main__":
    main()
