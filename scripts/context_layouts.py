"""Context complexity of generator presets, measured on layouts only.

Context complexity depends only on which classes a scene's layout places, so this runs the
selection and layout stages of ``assist3d generate`` (same seeds, same presets) and skips
rendering, which is most of a scene's time; many more scenes fit in the same time, which the
metric needs (its small-count bias, docs/metrics.md). ``--sparse`` lowers the object counts (12
floor, 4 wall, 2 on-top objects per support) so that the metric is not saturated.

    python scripts/context_layouts.py --presets pairing-0 pairing-0.33 pairing-0.66 pairing-1.0 --sparse
    python scripts/context_layouts.py --presets assist3d randomrooms holodeck-style no-context --scenes 200

Prints one JSON object {preset: {"scenes", "instances_per_scene", "classes_per_scene",
"context_complexity"}}.
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

SPARSE = {"selection": {"floor_count": 12, "wall_count": 4, "on_top_count": 2}}

_catalog = None


def _classes(job: tuple[str | None, str, dict, int]) -> tuple[str, int, list[str]]:
    global _catalog
    assets, preset, overrides, index = job
    if _catalog is None:
        _catalog = open_catalog(assets)
    cfg = apply_preset(overrides, preset)
    layout = build_layout(_catalog, cfg, scene_seed(cfg.seed, index), scene_index=index)
    return preset, len(layout.instances), sorted({inst.class_name for inst in layout.instances})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--assets", default=None, help="catalog folder (default: as assist3d generate)")
    ap.add_argument("--seed", type=int, default=0, help="dataset seed (as assist3d generate --seed)")
    ap.add_argument("--presets", nargs="+", default=["pairing-0", "pairing-0.33", "pairing-0.66", "pairing-1.0"])
    ap.add_argument("--sparse", action="store_true", help="12 floor, 4 wall, 2 on-top objects per support "
                                                          "instead of the presets' counts")
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    overrides = dict(SPARSE) if args.sparse else {}
    overrides["seed"] = args.seed
    jobs = [(args.assets, p, overrides, i) for p in args.presets for i in range(args.scenes)]
    with ProcessPoolExecutor(args.workers) as ex:
        results = list(ex.map(_classes, jobs, chunksize=4))
    out = {}
    for p in args.presets:
        rows = [(n, set(c)) for preset, n, c in results if preset == p]
        sets = [c for _, c in rows]
        out[p] = {"scenes": len(rows), "instances_per_scene": round(float(np.mean([n for n, _ in rows])), 2),
                  "classes_per_scene": round(float(np.mean([len(c) for c in sets])), 2),
                  "context_complexity": round(context_complexity(sets), 4)}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
