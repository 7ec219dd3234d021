"""Context complexity (and a quick geometry diversity) of generator presets, on layouts only.

Context complexity depends only on which classes a scene's layout places, so this runs the
selection and layout stages of ``assist3d generate`` (same seeds, same presets) and skips
rendering, which is most of a scene's time; many more scenes fit in the same time, which the
metric needs (its small-count bias, docs/metrics.md). ``--sparse`` lowers the object counts (12
floor, 4 wall, 2 on-top objects per support) so that the metric is not saturated.

``--geometry`` adds a geometry diversity computed from each placed instance's *asset mesh*
descriptor (the per-asset cache of ``assist3d cluster-assets``, ``<catalog>/features.npz``)
under one 64-code codebook fitted on an equal pool from every preset. ``assist3d metrics``
describes instances from their rendered points instead (partial views), so the two differ a
little; this one needs no rendering.

    python scripts/context_layouts.py --presets pairing-0 pairing-0.33 pairing-0.66 pairing-1.0 --sparse
    python scripts/context_layouts.py --presets assist3d randomrooms holodeck-style no-context --scenes 50 \\
        --assets /tmp/combo-lib --seed 1 --geometry

Prints one JSON object {preset: {"scenes", "instances_per_scene", "classes_per_scene",
"context_complexity"[, "distinct_assets", "geometry_diversity_mesh"]}}.
"""

from __future__ import annotations

import argparse
import json
import logging
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from assist3d.assets import open_catalog
from assist3d.bench.metrics.context import context_complexity
from assist3d.config.presets import apply_preset
from assist3d.core.rng import scene_seed
from assist3d.scene.layout import build_layout

SPARSE = {"selection": {"floor_count": 12, "wall_count": 4, "on_top_count": 2}}

_catalog = None


def _layout(job: tuple[str | None, str, dict, int]) -> tuple[str, list[tuple[str, str]]]:
    global _catalog
    assets, preset, overrides, index = job
    if _catalog is None:
        _catalog = open_catalog(assets)
    cfg = apply_preset(overrides, preset)
    layout = build_layout(_catalog, cfg, scene_seed(cfg.seed, index), scene_index=index)
    return preset, [(inst.asset, inst.class_name) for inst in layout.instances]


def _geometry(assets: str | None, presets: list[str], scenes: dict[str, list[list[tuple[str, str]]]]) -> dict:
    from assist3d.bench.metrics.clusters import asset_features
    from assist3d.bench.metrics.diversity import geometry_diversity
    from assist3d.bench.metrics.report import DatasetSummary, shared_codebook

    ids, feats = asset_features(open_catalog(assets))
    row = {a: i for i, a in enumerate(ids)}
    per = {p: feats[[row[a] for sc in scenes[p] for a, _ in sc if a in row]] for p in presets}
    # the codebook `assist3d metrics` would fit: an equal pool from every preset
    book = shared_codebook([DatasetSummary(p, features=f) for p, f in per.items()], seed=0)
    return {p: {"distinct_assets": len({a for sc in scenes[p] for a, _ in sc}),
                "geometry_diversity_mesh": round(geometry_diversity(per[p], book), 4)} for p in presets}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--assets", default=None, help="catalog folder (default: as assist3d generate)")
    ap.add_argument("--seed", type=int, default=0, help="dataset seed (as assist3d generate --seed)")
    ap.add_argument("--presets", nargs="+", default=["pairing-0", "pairing-0.33", "pairing-0.66", "pairing-1.0"])
    ap.add_argument("--sparse", action="store_true", help="12 floor, 4 wall, 2 on-top objects per support "
                                                          "instead of the presets' counts")
    ap.add_argument("--geometry", action="store_true", help="also the asset-mesh geometry diversity")
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    overrides = dict(SPARSE) if args.sparse else {}
    overrides["seed"] = args.seed
    jobs = [(args.assets, p, overrides, i) for p in args.presets for i in range(args.scenes)]
    with ProcessPoolExecutor(args.workers) as ex:
        results = list(ex.map(_layout, jobs, chunksize=4))
    scenes = {p: [inst for preset, inst in results if preset == p] for p in args.presets}
    out = {}
    for p in args.presets:
        sets = [{c for _, c in sc} for sc in scenes[p]]
        out[p] = {"scenes": len(sets), "instances_per_scene": round(float(np.mean([len(sc) for sc in scenes[p]])), 2),
                  "classes_per_scene": round(float(np.mean([len(c) for c in sets])), 2),
                  "context_complexity": round(context_complexity(sets), 4)}
    if args.geometry:
        for p, extra in _geometry(args.assets, args.presets, scenes).items():
            out[p].update(extra)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
