"""Measure layouts at the paper's settings: placed instances, check_layout problems, seconds.

Usage: python scripts/layout_stats.py [--assets DIR | --procedural N] [--scenes 50] [--seed 0]
       [--preset NAME] [--png-dir DIR]
Prints one JSON object. Scene k uses seed scene_seed(seed, k) and scene_index k (so half the
scenes use the complementary selection strategy, as in the paper).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections import Counter
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--assets", help="catalog folder (default: open_catalog's choice)")
    ap.add_argument("--procedural", type=int, default=None, help="use the built-in procedural library of N assets")
    ap.add_argument("--scenes", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--preset", default="assist3d")
    ap.add_argument("--png-dir", default=None, help="also write a top-down PNG per scene here")
    ap.add_argument("--no-check", action="store_true", help="skip check_layout (mesh-level checks)")
    args = ap.parse_args(argv)

    from assist3d.assets import open_catalog, procedural_library_dir
    from assist3d.config.presets import apply_preset
    from assist3d.core.rng import scene_seed
    from assist3d.scene.layout import build_layout

    cfg = apply_preset({}, args.preset)
    t0 = time.perf_counter()
    if args.procedural is not None:
        from assist3d.assets.catalog import Catalog

        root = procedural_library_dir(args.procedural, 0)
        if not Catalog.exists(root):
            from assist3d.assets.procedural import build_library

            build_library(root, count=args.procedural, seed=0)
        catalog = Catalog.open(root)
    else:
        catalog = open_catalog(args.assets, procedural_count=cfg.assets.procedural_count,
                               procedural_seed=cfg.assets.procedural_seed)
    load_s = time.perf_counter() - t0
    check = None
    if not args.no_check:
        from assist3d.scene.checks import check_layout as check

    placed, seconds, cpu, problems, per_group, dropped = [], [], [], [], Counter(), []
    reasons: Counter = Counter()
    budget_hits = 0
    check_s = 0.0
    for k in range(args.scenes):
        c0 = time.process_time()
        lay = build_layout(catalog, cfg, scene_seed(args.seed, k), scene_index=k)
        cpu.append(time.process_time() - c0)
        placed.append(len(lay.instances))
        seconds.append(lay.seconds)
        dropped.append(len(lay.dropped))
        per_group.update(lay.stats["placed"])
        budget_hits += int(lay.stats.get("placement", {}).get("budget_hit", 0))
        for d in lay.dropped:
            reasons[d.reason.split(":")[0][:60]] += 1
        if check is not None:
            c0 = time.perf_counter()
            problems.append(len(check(lay, catalog)))
            check_s += time.perf_counter() - c0
        if args.png_dir:
            from assist3d.export.topdown import render_topdown

            render_topdown(lay, catalog, Path(args.png_dir) / f"scene_{k:03d}.png")
    n = max(1, args.scenes)
    out = {
        "catalog": str(catalog.root),
        "assets": len(catalog),
        "preset": args.preset,
        "scenes": args.scenes,
        "mean_placed": round(statistics.fmean(placed), 2),
        "min_placed": min(placed),
        "mean_placed_per_group": {g: round(v / n, 2) for g, v in sorted(per_group.items())},
        "mean_dropped": round(statistics.fmean(dropped), 2),
        "top_drop_reasons": dict(reasons.most_common(6)),
        "groups_over_time_budget": budget_hits,
        "check_problems_total": sum(problems) if check is not None else None,
        "scenes_with_problems": sum(1 for p in problems if p) if check is not None else None,
        "median_seconds": round(statistics.median(seconds), 3),
        "max_seconds": round(max(seconds), 3),
        "median_cpu_seconds": round(statistics.median(cpu), 3),
        "max_cpu_seconds": round(max(cpu), 3),
        "catalog_load_seconds": round(load_s, 2),
        "check_seconds": round(check_s, 2),
    }
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
