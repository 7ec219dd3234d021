"""plan.md's measurement: per-scan AP50 / AP / AP25 of the network's own instances (`--method learned`) and of the
variant that gives the room's structural voxels foreground 0 before grouping, for one model on the real scans.

    PYTHONPATH=src python experiments/structure-2026-12-07/run.py MODEL.pt OUT.json [--eval SPEC ...]

Both sides go through `Predictor.segment` (the same frame, usable points and masks as `assist3d segment`); the
variant is registered here as a post-processing step, so nothing in the package changes for the measurement.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from assist3d.bench.evaluation.ap import match_scene, summarize
from assist3d.data import open_dataset
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.features import voxelize
from assist3d.learn.segmenter.geometric import GeometricConfig, structural_points
from assist3d.learn.segmenter.infer import instances, predict_scan
from assist3d.learn.segmenter.predictor import STEPS, Predictor, Step

SPECS = ["array:../shared/data/real/dev", "array:../shared/data/real/scannet_scene0451_01.npy"]
VARIANT = "learned-nostructure"


def learned_without_structure(model, cfg, coord, color, *, tta=False):
    """plan.md's variant: network voxels whose points are mostly structural get foreground 0."""
    coord = np.asarray(coord, np.float32)
    vox = voxelize(coord, cfg.net.voxel_size, color)
    fg, offset = predict_scan(model, cfg, coord, color, vox, tta=tta)
    on_plane = structural_points(coord, GeometricConfig())
    n_vox = len(vox.centres)
    share = np.bincount(vox.inverse, on_plane.astype(np.float64), n_vox) / np.bincount(vox.inverse, minlength=n_vox)
    fg = np.where(share > 0.5, np.float32(0), fg)
    return instances(vox, fg, offset, cfg.cluster)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("model", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--eval", action="append", help="reader specs (default: the dev scans and scene0451_01)")
    a = ap.parse_args()
    STEPS.add(VARIANT, Step(learned_without_structure))
    loaded = load_segmenter(a.model)
    result: dict[str, dict] = {"model": str(a.model)}
    for method in ("learned", VARIANT):
        pred = Predictor(loaded, method)
        per_scene, matches, seconds = {}, [], {}
        for spec in a.eval or SPECS:
            ds = open_dataset(spec)
            for sid in ds.scene_ids:
                s = ds.load(sid)
                t0 = time.perf_counter()
                seg = pred.segment(s.coord, s.color, name=sid, where=str(ds.root))
                seconds[sid] = round(time.perf_counter() - t0, 2)
                m = match_scene(s.instance, seg.masks, seg.scores, valid=s.valid, scene_id=sid)
                matches.append(m)
                one = summarize([m])
                per_scene[sid] = {k: round(float(one[k]), 4) for k in ("AP", "AP50", "AP25")} | {
                    "num_pred": int(one.num_pred), "seconds": seconds[sid]}
                print(method, sid, per_scene[sid], flush=True)
        overall = summarize(matches)
        result[method] = {"per_scene": per_scene, **{k: round(float(overall[k]), 4) for k in ("AP", "AP50", "AP25")}}
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
