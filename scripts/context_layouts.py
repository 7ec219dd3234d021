"""Context complexity against the pairing probability q, measured on layouts only.

Context complexity depends only on which classes a scene's layout places, so this runs the
selection and layout stages of ``assist3d generate`` (same seeds, same presets) and skips
rendering, which is ~95 % of a scene's time. Scenes are kept sparse by default (12 floor, 4 wall,
2 on-top objects per support) so that the metric is not saturated (see docs/metrics.md).

    python scripts/context_vs_pairing.py [--scenes 100] [--workers 2] [--assets DIR] [--dense]

Prints one JSON object {q: {"scenes", "classes_per_scene", "context_complexity"}}.
"""

from __future__ import annotations

import argparse
import json
import logging
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from assist3d.assets import open_catalog
from assist3d.metrics.context import context_complexity
from assist3d.presets import apply_preset
from assist3d.rng import scene_seed
from assist3d.scene.layout import build_layout

LEVELS = ("0", "0.33", "0.66", "1.0")
SPARSE = {"selection": {"floor_count": 12, "wall_count": 4, "on_top_count": 2}}

_catalog = None


def _classes(job: tuple[str | None, str, dict, int]) -> tuple[str, list[str]]:
    global _catalog
    assets, level, overrides, index = job
    if _catalog is None:
        _catalog = open_catalog(assets)
    cfg = apply_preset(overrides, f"pairing-{level}")
    layout = build_layout(_catalog, cfg, scene_seed(cfg.seed, index), scene_index=index)
    return level, sorted({inst.class_name for inst in layout.instances})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--assets", default=None, help="catalog folder (default: as assist3d generate)")
    ap.add_argument("--dense", action="store_true", help="the paper's object counts instead of sparse scenes")
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    overrides = {} if args.dense else SPARSE
    jobs = [(args.assets, q, overrides, i) for q in LEVELS for i in range(args.scenes)]
    with ProcessPoolExecutor(args.workers) as ex:
        results = list(ex.map(_classes, jobs, chunksize=8))
    out = {}
    for q in LEVELS:
        sets = [set(c) for level, c in results if level == q]
        out[q] = {"scenes": len(sets), "classes_per_scene": round(float(np.mean([len(s) for s in sets])), 2),
                  "context_complexity": round(context_complexity(sets), 4)}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
