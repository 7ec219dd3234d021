"""The plan's two decisions (plan.md, "Reading"), applied to the finished points in per_seed/.

    python experiments/scaling-2026-12-05/decide.py

1. Shipped model: among the points with two or more seeds, the one with the highest mean learned AP50
   over the 6 rooms replaces the shipped model only if that mean exceeds the shipped model's (measured
   the same way: the newest of SHIPPED_EVALS, today segmenter-v3.pt's) by more than the point's seed spread
   (std over seeds).
2. `segment` default, for the chosen model (the best point if it replaces the shipped model, else the
   shipped model): hybrid stays only if it is above the network alone in at least 5 of the 6 rooms and the
   mean difference is positive with a 95 % interval (rooms resampled, bench/evaluation/compare.py, as
   scripts/compare_probes.py) that excludes 0; otherwise the network alone (--method learned).
Prints the figures behind each decision; decides nothing while no point has two seeds.
"""

from __future__ import annotations

import json
import statistics

from assist3d.bench.evaluation.compare import mean_over_runs, paired_comparison

from summarize import HERE, load, room_means  # the same reading as the table


def six_room_mean(per_scene: dict) -> float:
    rm = room_means(per_scene)
    return sum(rm.values()) / len(rm)


def hybrid_rule(learned: dict[str, float], hybrid: dict[str, float]) -> tuple[bool, str]:
    lr = room_means({s: {"AP50": v} for s, v in learned.items()})
    hr = room_means({s: {"AP50": v} for s, v in hybrid.items()})
    ahead = sum(hr[r] > lr[r] for r in lr)
    c = paired_comparison(learned, hybrid)
    keep = ahead >= 5 and c.ci95[0] > 0
    text = (f"hybrid - learned per room: " + ", ".join(f"{r} {hr[r] - lr[r]:+.3f}" for r in lr)
            + f"; hybrid ahead in {ahead} of {len(lr)} rooms; mean per-scan difference {c.mean_diff:+.3f}, "
            f"95 % interval over rooms [{c.ci95[0]:+.3f}, {c.ci95[1]:+.3f}]")
    return keep, text


#: scripts/hybrid_eval.py's figures of each model shipped so far, the newest first: the rule measures a point
#: against the model users get now
SHIPPED_EVALS = ("hybrid_eval-shipped-v3.json", "hybrid_eval-shipped-v2.json", "hybrid_eval-shipped.json")


def main() -> None:
    points = {k: v for k, v in load().items() if len(v) >= 2}
    shipped_file = next(HERE / "shipped" / f for f in SHIPPED_EVALS if (HERE / "shipped" / f).is_file())
    name, model = next(iter(json.loads(shipped_file.read_text())["models"].items()))
    print(f"the shipped model: {name.rsplit('/', 1)[-1]} ({shipped_file.name})")
    ship = {kind: {s: v["AP50"] for g in model[kind] for s, v in g["scans"].items()} for kind in ("learned", "hybrid")}
    ship_mean = six_room_mean({s: {"AP50": v} for s, v in ship["learned"].items()})
    if not points:
        print("no point with two seeds yet: nothing is decided")
        return
    scored = {}
    for key, seeds in points.items():
        per_seed = [six_room_mean(r["per_scene"]) for r in seeds.values()]
        scored[key] = (statistics.fmean(per_seed), statistics.stdev(per_seed), per_seed)
    best = max(scored, key=lambda k: scored[k][0])
    mean, sd, per_seed = scored[best]
    replace = mean - ship_mean > sd
    print(f"best point with 2+ seeds: {best[0]} steps, {best[1]} scenes: learned 6-room AP50 {mean:.3f} "
          f"(seeds {', '.join(f'{x:.3f}' for x in per_seed)}, spread {sd:.3f}) against the shipped model's "
          f"{ship_mean:.3f}: {'REPLACES the shipped model' if replace else 'the shipped model stays'} "
          f"(needs a lead above {sd:.3f}, has {mean - ship_mean:+.3f})")
    if replace:
        runs = list(points[best].values())
        learned = mean_over_runs([{s: v["AP50"] for s, v in r["per_scene"].items()} for r in runs])
        hybrid = mean_over_runs([{s: v["AP50"] for s, v in r["hybrid"]["per_scene"].items()} for r in runs])
        which = f"the {best[0]}-step point (mean over its seeds)"
    else:
        learned, hybrid, which = ship["learned"], ship["hybrid"], "the shipped model"
    keep, text = hybrid_rule(learned, hybrid)
    print(f"segment default, for {which}: {text}: "
          + ("hybrid inference is the default" if keep else "the network alone (--method learned) is the default"))


if __name__ == "__main__":
    main()
