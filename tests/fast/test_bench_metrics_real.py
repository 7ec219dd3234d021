"""The dataset metrics on the real ScanNet scan (skipped when ../shared is absent)."""

from __future__ import annotations

import math

import numpy as np

from assist3d.bench.metrics.report import metrics_table, shared_codebook, summarize_dataset


def test_metrics_on_real_scan(real_scan_path):
    raw = np.load(real_scan_path)
    objects = np.unique(raw[(raw[:, 6] >= 3) & (raw[:, 6] <= 20), 7])
    summary = summarize_dataset(f"array:{real_scan_path}")
    assert summary.scenes == 1
    assert summary.instances == len(objects)
    # every object instance big enough for a descriptor has one, and they are finite
    assert 0.8 * len(objects) <= len(summary.features) <= len(objects)
    assert np.isfinite(summary.features).all()
    # classes come from the instances' majority semantic labels: a handful of ScanNet classes
    assert 2 <= len(summary.scene_classes[0]) <= 18
    row = metrics_table([summary], shared_codebook([summary], seed=0))[f"array:{real_scan_path}"]
    assert row["layout_score"] is None and "layout" in row["notes"]["layout_score"]
    # one scene: every class shares it with every other class
    assert row["context_complexity"] == 1.0
    assert 0.0 < row["geometry_diversity"] <= math.log(row["codes"]) + 1e-3  # values are rounded to 4 decimals
