"""Inference-time variants of the CPU segmenter, scored on real scans (experiments/fidelity-log.md, "Inference
variants"). The network is run once per scan (plus 7 rotated / mirrored copies for test-time
augmentation) and the per-voxel outputs are cached; the variants only change what happens after:

    base      the shipped clustering: foreground voxels shifted by their offsets, linked within 7 cm
    tta       foreground probability and offsets averaged over 8 copies (4 rotations about z x mirror)
    ms        proposals at 5, 7 and 10 cm linking radius, merged by non-maximum suppression (IoU 0.5)
    dual      plus proposals from the unshifted foreground voxels (6 cm), as PointGroup does
    (combinations with '+', and 'nms3' for an NMS threshold of 0.3)

    python experiments/tools/inference_variants.py MODEL.pt CACHE.npz [--variants base,tta,ms,tta+ms]
        [--eval array:../shared/data/real/dev --eval array:../shared/data/real/scannet_scene0451_01.npy]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import torch

from assist3d.data import open_dataset
from assist3d.bench.evaluation.ap import match_scene, summarize
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.cluster import mask_nms, radius_components
from assist3d.learn.segmenter.features import voxelize
from assist3d.learn.segmenter.infer import TTA_TURNS, predict_voxels_tta


def network_outputs(model_path: str, specs: list[str]) -> dict[str, dict[str, np.ndarray]]:
    """Per scan: voxel centres, point->voxel index, GT, and (8, V) fg / (8, V, 3) offsets (copy 0 = as is)."""
    loaded = load_segmenter(model_path)
    cfg = loaded.config
    out = {}
    for spec in specs:
        ds = open_dataset(spec)
        for sid in ds.scene_ids:
            s = ds.load(sid)
            vox = voxelize(s.coord.astype(np.float32), cfg.net.voxel_size, s.color)
            fgs, offs = [], []
            for turn in TTA_TURNS:
                fg, off = predict_voxels_tta(loaded.model, cfg, s.coord, s.color, vox, turns=(turn,))
                fgs.append(fg)
                offs.append(off)
            out[sid] = {"centres": vox.centres, "inverse": vox.inverse, "instance": s.instance, "valid": s.valid,
                        "fg": np.stack(fgs), "off": np.stack(offs)}
            print("network outputs:", sid, flush=True)
    return out


def save_cache(path: Path, data: dict) -> None:
    flat = {f"{sid}/{k}": v for sid, d in data.items() for k, v in d.items()}
    np.savez_compressed(path, **flat)


def load_cache(path: Path) -> dict:
    data: dict[str, dict] = {}
    with np.load(path, allow_pickle=False) as z:
        for key in z.files:
            sid, k = key.split("/")
            data.setdefault(sid, {})[k] = z[key]
    return data


def _proposals(xyz: np.ndarray, rows: np.ndarray, radius: float, min_voxels: int = 6) -> list[np.ndarray]:
    comp = radius_components(xyz, radius)
    sizes = np.bincount(comp)
    return [rows[comp == c] for c in np.flatnonzero(sizes >= min_voxels)]


def variant(d: dict, name: str) -> tuple[np.ndarray, np.ndarray]:
    parts = set(name.split("+"))
    fg = d["fg"].mean(0) if "tta" in parts else d["fg"][0]
    off = d["off"].mean(0) if "tta" in parts else d["off"][0]
    rows = np.flatnonzero(fg > 0.5)
    shifted = d["centres"][rows] + off[rows]
    props = []
    for r in ((0.05, 0.07, 0.10) if "ms" in parts else (0.07,)):
        props += _proposals(shifted, rows, r)
    if "dual" in parts:
        props += _proposals(d["centres"][rows], rows, 0.06)
    n_points = len(d["inverse"])
    if not props:
        return np.zeros((0, n_points), bool), np.zeros(0, np.float32)
    mv = np.zeros((len(props), len(fg)), bool)
    for i, p in enumerate(props):
        mv[i, p] = True
    size = mv.sum(1)
    score = (mv * fg).sum(1) / size * np.minimum(1.0, size / 40.0) ** 0.5
    if len(props) > 1 and parts & {"ms", "dual"}:
        keep = mask_nms(mv, score, 0.3 if "nms3" in parts else 0.5)
        mv, score = mv[keep], score[keep]
    return mv[:, d["inverse"]], score.astype(np.float32)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("model")
    ap.add_argument("cache", type=Path)
    ap.add_argument("--variants", default="base,tta,ms,tta+ms,dual,tta+dual,tta+ms+dual,tta+ms+nms3")
    ap.add_argument("--eval", action="append")
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    specs = a.eval or ["array:../shared/data/real/dev", "array:../shared/data/real/scannet_scene0451_01.npy"]
    if not a.cache.exists():
        save_cache(a.cache, network_outputs(a.model, specs))
    data = load_cache(a.cache)
    print("| variant | AP | AP50 | AP25 | AR | AP50 scene0451_01 |\n|---|---:|---:|---:|---:|---:|")
    for name in a.variants.split(","):
        dev, other = [], []
        for sid, d in data.items():
            masks, scores = variant(d, name)
            m = match_scene(d["instance"], masks, scores, valid=d["valid"], scene_id=sid)
            (other if "0451" in sid else dev).append(m)
        s = summarize(dev)
        s451 = f"{summarize(other)['AP50']:.3f}" if other else "-"
        print(f"| {name} | {s['AP']:.3f} | {s['AP50']:.3f} | {s['AP25']:.3f} | {s['AR']:.3f} | {s451} |", flush=True)


if __name__ == "__main__":
    main()
