# How many training seeds a recipe decision needs on the 10 dev scans (experiments/fidelity-log.md, "How many
# seeds a decision needs"). The per-seed dev AP50 figures below are copied from the tables of
# experiments/fidelity-log.md (every 821-step recipe with two or more seeds); the seed standard deviation is
# pooled over recipes (each recipe's own mean removed), and the seeds per recipe for a two-sided 5 %
# test with 80 % power follow the normal approximation n = 2 (z_0.975 + z_0.8)^2 sd^2 / d^2 (the sd taken
# as known), and with a t test when the sd must come from the compared seeds alone. The pooled figure
# leans on the three recipes of widest spread (top cut, both deeper encoders), so it is also given
# without them.
#   python power.py
import numpy as np
from scipy import stats

RECIPES = {  # recipe: (learned dev AP50 per seed, hybrid dev AP50 per seed)
    "shipped recipe, reruns (section 'The seed spread of the shipped recipe')": ([0.145, 0.143, 0.154], [0.199, 0.233, 0.244]),
    "weight averaging (the default)": ([0.178, 0.157], [0.247, 0.254]),
    "smaller jitter": ([0.205, 0.178], [0.233, 0.271]),
    "deeper encoder": ([0.206, 0.143], [0.253, 0.203]),
    "deeper encoder + weight averaging": ([0.284, 0.180], [0.262, 0.238]),
    "top cut (seeds 0-3)": ([0.245, 0.223, 0.147, 0.163], [0.296, 0.291, 0.233, 0.208]),
}
Z = stats.norm.ppf(0.975) + stats.norm.ppf(0.8)
WIDEST = ("deeper encoder", "deeper encoder + weight averaging", "top cut (seeds 0-3)")


def report(recipes: dict, title: str) -> None:
    print(f"== {title} ({len(recipes)} recipes, {sum(len(v[0]) for v in recipes.values())} models)")
    for j, name in enumerate(("learned", "hybrid")):
        resid = [np.asarray(v[j]) - np.mean(v[j]) for v in recipes.values()]
        df = sum(len(r) - 1 for r in resid)
        sd = float(np.sqrt(sum((r ** 2).sum() for r in resid) / df))
        lo, hi = (sd * np.sqrt(df / stats.chi2.ppf(q, df)) for q in (0.975, 0.025))
        print(f"{name}: pooled seed sd {sd:.3f} (95 % interval {lo:.3f}-{hi:.3f}, {df} degrees of freedom)")
        print("  smallest difference found 4 times in 5 with K seeds per recipe (sd known): "
              + ", ".join(f"K={k} {Z * sd * np.sqrt(2 / k):.3f}" for k in (2, 3, 4, 8)))
        # the same when the two recipes' own K seeds are all there is to estimate the sd from (t test)
        print("  ... with the sd estimated from those seeds alone (t test): "
              + ", ".join(f"K={k} {(stats.t.ppf(0.975, 2 * k - 2) + stats.t.ppf(0.8, 2 * k - 2)) * sd * np.sqrt(2 / k):.3f}"
                          for k in (2, 3, 4, 8)))
        print("  seeds per recipe to find a difference d 4 times in 5 (sd known): "
              + ", ".join(f"d={d} {int(np.ceil(2 * (Z * sd / d) ** 2))}" for d in (0.02, 0.03, 0.05)))


report(RECIPES, "every recipe")
report({k: v for k, v in RECIPES.items() if k not in WIDEST}, "without the three recipes of widest spread")
