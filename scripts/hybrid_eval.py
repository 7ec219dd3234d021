"""Learned vs hybrid inference of the CPU segmenter over many trained models, on real scans
(experiments/fidelity-log.md, "Hybrid inference"). Each model's network runs once per scan; the geometric
components and the superpoints do not depend on the model and are computed once per scan.

    python scripts/hybrid_eval.py MODEL.pt [MODEL.pt ...] --out hybrid.json
        [--eval array:../shared/data/real/dev --eval array:../shared/data/real/scannet_scene0451_01.npy]
        [--tta] [--refine-planes N]

Rows: ``geometric`` and ``geometric+snap`` (no model; the control: the reference, ``GeometricConfig()``,
whose planes are not refit), then per model ``learned``
(what ``assist3d probe`` scores), ``hybrid`` (what ``assist3d segment`` does by default, with
``HYBRID_GEOMETRIC``'s plane refit since 2026-11-28; figures before that date were made without it),
``hybrid_v1`` (the first hybrid recipe, without the fallback proposals). The variants measured and not
adopted (stability ranking, structural planes dropped, superpoint-agreement ranking) have left the code;
their rows are in the result files of experiments/ made before that. ``--tta``
adds ``learned+tta`` and ``hybrid+tta``: the same with the network's outputs averaged over 8 copies
of each scan (4 quarter turns about z, with and without a mirror; ``infer.predict_voxels_tta``).
AP50 is over the scans of the first --eval spec; each further spec is reported on its own; every
row also holds its per-scan AP / AP50 / AP25 (``scans``) for ``scripts/compare_probes.py``.
A MODEL argument of comma-joined files (``A.pt,B.pt``) is a seed ensemble: the foreground
probabilities and offsets of its members are averaged before the rows above are formed (members must
share the voxel size; the first member's clustering settings are used).
"""

from __future__ import annotations

import argparse
import time
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
import torch

from assist3d.data import open_dataset
from assist3d.bench.evaluation.ap import match_scene, summarize
from assist3d.bench.evaluation.compare import room_means
from assist3d.core.fileio import write_json_atomic
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.features import voxel_features, voxelize
from assist3d.learn.segmenter.geometric import segment_geometric
from assist3d.learn.segmenter.hybrid import HYBRID_GEOMETRIC, HybridConfig, combine
from assist3d.learn.segmenter.infer import instances, predict_voxels, predict_voxels_tta
from assist3d.learn.segmenter.superpoints import snap_masks, superpoints

VARIANTS = {
    "hybrid": HybridConfig(),
    "hybrid_v1": HybridConfig(fallback_radius=None),
}


def _metrics(matches: list) -> dict:
    s = summarize(matches)
    per_scan = {m.scene_id: summarize([m]) for m in matches}
    per_room = {r: round(v, 4) for r, v in room_means({sid: v["AP50"] for sid, v in per_scan.items()}).items()}
    scans = {sid: {k: round(float(v[k]), 4) for k in ("AP", "AP50", "AP25")} for sid, v in per_scan.items()}
    return {k: round(float(s[k]), 4) for k in ("AP", "AP50", "AP25", "AR")} | {"rooms": per_room, "scans": scans}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("models", nargs="+")
    ap.add_argument("--eval", action="append")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--tta", action="store_true", help="also the rows learned+tta and hybrid+tta")
    ap.add_argument("--refine-planes", type=int, default=None, metavar="N",
                    help="plane refits of the geometric components that the hybrid rows use (default: "
                         "HYBRID_GEOMETRIC's, today's; 0 reproduces the hybrid figures made before the refit); "
                         "the control rows never refit")
    a = ap.parse_args()
    hyb_geo = HYBRID_GEOMETRIC if a.refine_planes is None else replace(HYBRID_GEOMETRIC, refine=a.refine_planes)
    torch.set_num_threads(a.threads)
    specs = a.eval or ["array:../shared/data/real/dev", "array:../shared/data/real/scannet_scene0451_01.npy"]
    # (group, scene_id, sample, hybrid inference's geometric components, superpoints); the control rows
    # score the reference itself (GeometricConfig(), no plane refit)
    scans, reference = [], []
    for g, spec in enumerate(specs):
        ds = open_dataset(spec)
        for sid in ds.scene_ids:
            s = ds.load(sid)
            scans.append((g, sid, s, segment_geometric(s.coord, hyb_geo), superpoints(s.coord)))
            reference.append(segment_geometric(s.coord))
            print("prepared", sid, flush=True)

    def score(preds: list) -> list[dict]:
        groups: list[list] = [[] for _ in specs]
        for (g, sid, s, *_), (masks, scores) in zip(scans, preds):
            groups[g].append(match_scene(s.instance, masks, scores, valid=s.valid, scene_id=sid))
        return [_metrics(m) for m in groups]

    result: dict = {"eval": specs, "hybrid_geometric": asdict(hyb_geo), "control": {}, "models": {}}
    result["control"]["geometric"] = score([(geo.masks, geo.scores) for geo in reference])
    result["control"]["geometric+snap"] = score([(snap_masks(geo.masks, segs), geo.scores)
                                                 for geo, (*_, segs) in zip(reference, scans)])
    for path in a.models:
        t0 = time.perf_counter()
        members = [load_segmenter(p) for p in path.split(",")]
        cfg = members[0].config
        if any(m.config.net.voxel_size != cfg.net.voxel_size for m in members):
            raise SystemExit(f"{path}: ensemble members must share the voxel size")
        learned: list = []
        hybrid: dict[str, list] = {name: [] for name in VARIANTS}
        tta: dict[str, list] = {"learned+tta": [], "hybrid+tta": []}
        for _, _, s, geo, segs in scans:
            vox = voxelize(s.coord.astype(np.float32), cfg.net.voxel_size, s.color)
            outs = [predict_voxels(m.model, vox.coords, voxel_features(vox, use_color=m.config.net.use_color))
                    for m in members]
            fg, off = np.mean([o[0] for o in outs], 0), np.mean([o[1] for o in outs], 0)
            inst = instances(vox, fg, off, cfg.cluster)
            learned.append((inst.masks, inst.scores))
            for name, variant in VARIANTS.items():
                h = combine(inst, vox, fg, off, cfg.cluster, geo.masks, segs, hybrid=variant)
                hybrid[name].append((h.masks, h.scores))
            if a.tta:
                outs = [predict_voxels_tta(m.model, m.config, s.coord, s.color, vox) for m in members]
                fg, off = np.mean([o[0] for o in outs], 0), np.mean([o[1] for o in outs], 0)
                inst = instances(vox, fg, off, cfg.cluster)
                tta["learned+tta"].append((inst.masks, inst.scores))
                h = combine(inst, vox, fg, off, cfg.cluster, geo.masks, segs)
                tta["hybrid+tta"].append((h.masks, h.scores))
        rows = hybrid | (tta if a.tta else {})
        result["models"][path] = {"learned": score(learned)} | {name: score(p) for name, p in rows.items()}
        r = result["models"][path]
        ap50 = {k: " / ".join(f"{x['AP50']:.3f}" for x in v) for k, v in r.items()}
        print(f"{path}: AP50 " + ", ".join(f"{k} {v}" for k, v in ap50.items()) + f" ({time.perf_counter() - t0:.0f} s)",
              flush=True)
        write_json_atomic(a.out, result)
    write_json_atomic(a.out, result)


if __name__ == "__main__":
    main()
