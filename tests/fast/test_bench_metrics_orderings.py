"""The paper's generator orderings on the layouts of 50 scenes per generator, over the Sweet Home 3D
catalogs plus the procedural library (702 classes, the closest offline to the paper's 800).

Slow (~2 min on 2 cores: import, layouts, asset descriptors), so it is kept out of the default
run; ``scripts/compare_generators.sh`` measures the same orderings on fully rendered datasets
(docs/metrics.md). Run with ``pytest -m slow tests/fast/test_bench_metrics_orderings.py``.
"""

from __future__ import annotations

import pytest

from assist3d.assets.catalog import Catalog
from assist3d.assets.procedural import build_library
from assist3d.assets.sh3d import import_sh3d
from assist3d.bench.metrics.clusters import asset_features
from assist3d.bench.metrics.context import context_complexity
from assist3d.bench.metrics.diversity import geometry_diversity
from assist3d.bench.metrics.plausibility import score_layout
from assist3d.bench.metrics.report import DatasetSummary, shared_codebook
from assist3d.config.presets import apply_preset
from assist3d.core.rng import scene_seed
from assist3d.scene.layout import build_layout

PRESETS = ("assist3d", "randomrooms", "holodeck-style", "no-context")


@pytest.mark.acceptance
def test_generator_orderings_on_a_large_catalog(tmp_path, sh3d_dir):
    import numpy as np

    cat = Catalog.open_or_create(tmp_path / "lib")
    import_sh3d(cat, workers=2)
    cat = build_library(tmp_path / "lib", count=2000, seed=0, workers=2)
    assert len({r.class_name for r in cat.records}) >= 600
    ids, feats = asset_features(cat)
    row = {a: i for i, a in enumerate(ids)}
    cc, per, ls = {}, {}, {}
    for p in PRESETS:
        cfg = apply_preset({}, p)
        layouts = [build_layout(cat, cfg, scene_seed(cfg.seed, i), scene_index=i) for i in range(50)]
        cc[p] = context_complexity([{x.class_name for x in lay.instances} for lay in layouts])
        per[p] = feats[[row[x.asset] for lay in layouts for x in lay.instances]]
        ls[p] = float(np.mean([score_layout(lay, cat).score for lay in layouts]))
    book = shared_codebook([DatasetSummary(p, features=f) for p, f in per.items()], seed=0)
    gd = {p: geometry_diversity(f, book) for p, f in per.items()}
    # geometry diversity: ASSIST-3D and RandomRooms above Holodeck-style
    assert min(gd["assist3d"], gd["randomrooms"]) > gd["holodeck-style"], gd
    # context complexity: RandomRooms <= ASSIST-3D < without context < Holodeck-style
    assert cc["randomrooms"] <= cc["assist3d"] < cc["no-context"] < cc["holodeck-style"], cc
    # layout score: ASSIST-3D and Holodeck-style far above RandomRooms
    assert min(ls["assist3d"], ls["holodeck-style"]) > ls["randomrooms"] + 10, ls
