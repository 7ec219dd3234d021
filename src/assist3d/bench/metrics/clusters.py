"""Per-asset shape features (cached in the catalog) and the k-means shape clusters used by the
paper's geometry-diversity ablation (5 clusters; generate from the first k with `clusters-k`)."""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
from scipy.cluster.vq import kmeans2

from ...assets.catalog import Catalog
from ...core import reading
from ...core.errors import AssetError, DataError
from ...core.fileio import write_npz_atomic
from ...core.rng import make_rng
from .features import FEATURE_DIM, mesh_descriptor

log = logging.getLogger(__name__)

FEATURES_FILE = "features.npz"


def asset_features(catalog: Catalog, *, seed: int = 0) -> tuple[list[str], np.ndarray]:
    """Descriptors of every asset's mesh, read from / added to ``<catalog>/features.npz``.

    Returns (asset ids, (n, FEATURE_DIM) float32). Each asset's descriptor depends only on its
    mesh and the seed, so the cache stays valid when assets are added.
    """
    path = catalog.root / FEATURES_FILE
    cached: dict[str, np.ndarray] = {}
    if path.is_file():
        try:
            z = reading.read_npz(path, keys=("seed", "features", "ids"))
            # caches written before 0-d arrays were kept as such hold the seed as shape (1,)
            if int(np.asarray(z["seed"]).reshape(-1)[0]) == seed and z["features"].shape[1:] == (FEATURE_DIM,):
                cached = dict(zip(z["ids"].tolist(), z["features"]))
        except (DataError, IndexError, TypeError, ValueError):
            log.warning("%s: unreadable feature cache, recomputing", path)
    ids, feats, dirty = [], [], False
    for rec in catalog.records:
        f = cached.get(rec.id)
        if f is None:
            f = mesh_descriptor(catalog.load_mesh(rec), rng=make_rng(seed, "asset-features", rec.id))
            if f is None:
                log.warning("asset %s: degenerate mesh, no shape feature", rec.id)
                continue
            dirty = True
        ids.append(rec.id)
        feats.append(np.asarray(f, np.float32))
    arr = np.stack(feats) if feats else np.zeros((0, FEATURE_DIM), np.float32)
    if dirty:
        write_npz_atomic(path, ids=np.asarray(ids), features=arr, seed=np.asarray(seed))
    return ids, arr


def cluster_assets(catalog: Catalog, *, k: int = 5, seed: int = 0) -> dict[int, int]:
    """Assign every asset a shape cluster 0..k-1 (k-means on standardised features) and save the
    catalog. Clusters are numbered by decreasing size. Returns {cluster: asset count}."""
    ids, feats = asset_features(catalog, seed=seed)
    if len(ids) < k:
        raise AssetError(f"{catalog.root}: {len(ids)} assets with features, fewer than k = {k} clusters")
    z = (feats - feats.mean(0)) / np.maximum(feats.std(0), 1e-6)
    _, labels = kmeans2(z.astype(np.float64), k, iter=50, minit="++", seed=make_rng(seed, "clusters"))
    sizes = np.bincount(labels, minlength=k)
    order = np.argsort(-sizes, kind="stable")
    remap = np.empty(k, np.int64)
    remap[order] = np.arange(k)
    labels = remap[labels]
    for aid, lab in zip(ids, labels):
        catalog.update_record(replace(catalog.get(aid), cluster=int(lab)))
    catalog.save()
    return {int(c): int(n) for c, n in enumerate(np.bincount(labels, minlength=k))}
