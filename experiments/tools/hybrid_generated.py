"""Hybrid inference variants on held-out generated scenes (experiments/fidelity-log.md, "Fallback proposals"):
how the fallback proposals do where the network is in its own domain (the stability ranking it also scored has left the code).

    python experiments/tools/hybrid_generated.py MODEL.pt [MODEL.pt ...] --data assist3d:HELD_OUT [--scenes 60]
        [--out generated.json]

HELD_OUT is a generated dataset none of the models was trained on (experiments/fidelity-log.md used dataset
seed 1: ``assist3d generate --num-scenes 180 --seed 1 --preset assist3d``). Scenes are thinned to
~2.5 points per occupied 5 cm voxel like the real scans (seeded by the scene id, as in
``experiments/tools/proposal_scorer.py``); every generated instance counts as an object. Rows per model:
``learned`` (the network's instances), ``hybrid_v1`` (the first hybrid recipe), ``hybrid`` (the
default of ``assist3d segment``); AP, AP50, AP25 and AR over the scenes.
"""

from __future__ import annotations

import argparse
import json
import zlib
from pathlib import Path

import numpy as np
import torch

from assist3d.data import open_dataset
from assist3d.bench.evaluation.ap import match_scene, summarize
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.features import voxel_features, voxelize
from assist3d.learn.segmenter.geometric import segment_geometric
from assist3d.learn.segmenter.hybrid import HybridConfig, combine
from assist3d.learn.segmenter.infer import instances, predict_voxels
from assist3d.learn.segmenter.superpoints import superpoints

VARIANTS = {
    "hybrid_v1": HybridConfig(fallback_radius=None),
    "hybrid": HybridConfig(),
}


def thinned(sid: str, coord: np.ndarray, *arrays: np.ndarray) -> list[np.ndarray]:
    """The scene's points kept with probability 2.5 x occupied 5 cm voxels / points (seeded by ``sid``)."""
    keep_p = min(1.0, 2.5 * len(voxelize(coord, 0.05).counts) / len(coord))
    keep = np.random.default_rng(zlib.crc32(sid.encode())).random(len(coord)) < keep_p
    return [coord[keep]] + [a[keep] for a in arrays]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("models", nargs="+")
    ap.add_argument("--data", required=True)
    ap.add_argument("--scenes", type=int, default=60)
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args()
    torch.set_num_threads(1)
    ds = open_dataset(a.data)
    scenes = []  # model-independent parts: points, truth, geometric component per point, superpoints
    for sid in ds.scene_ids[: a.scenes]:
        s = ds.load(sid)
        coord, inst, valid = thinned(sid, s.coord.astype(np.float32), np.asarray(s.instance), np.asarray(s.valid))
        scenes.append((sid, coord, inst, valid, segment_geometric(coord).labels, superpoints(coord)))
        print("prepared", sid, flush=True)
    result: dict = {"data": a.data, "scenes": len(scenes), "models": {}}
    for path in a.models:
        loaded = load_segmenter(path)
        cfg = loaded.config
        matches: dict[str, list] = {name: [] for name in ("learned", *VARIANTS)}
        for sid, coord, inst, valid, geo_labels, segs in scenes:
            vox = voxelize(coord, cfg.net.voxel_size)
            fg, off = predict_voxels(loaded.model, vox.coords, voxel_features(vox, use_color=cfg.net.use_color))
            learned = instances(vox, fg, off, cfg.cluster)
            matches["learned"].append(match_scene(inst, learned.masks, learned.scores, valid=valid, scene_id=sid))
            components = geo_labels[None, :] == np.arange(geo_labels.max() + 1)[:, None]
            for name, variant in VARIANTS.items():
                seg = combine(learned, vox, fg, off, cfg.cluster, components, segs, hybrid=variant)
                matches[name].append(match_scene(inst, seg.masks, seg.scores, valid=valid, scene_id=sid))
        row = {name: {k: round(float(summarize(m)[k]), 4) for k in ("AP", "AP50", "AP25", "AR")}
               for name, m in matches.items()}
        result["models"][path] = row
        print(path, json.dumps({name: r["AP50"] for name, r in row.items()}), flush=True)
        if a.out:
            a.out.write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
