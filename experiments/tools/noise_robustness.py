"""How the segmenter holds up when a scan is noisier than ScanNet's reconstructed meshes.

ScanNet's points are vertices of a TSDF-fused, smoothed mesh; many users' scans are not (raw fused
depth points, a LiDAR sweep). This adds seeded Gaussian noise of standard deviation SIGMA metres
(per axis) to every point of each real scan and segments it as ``assist3d segment`` does, scored
against the scan's own labels:

    python experiments/tools/noise_robustness.py --sigma 0 0.0025 0.005 0.01 --out noise.json
        [--model MODEL.pt] [--eval array:../shared/data/real/dev --eval array:...scene0451_01.npy]
        [--denoise 0 1]  (denoise_points below: off and on)

    python experiments/tools/noise_robustness.py --summarize noise-seed*.json   (mean ± std over the files' seeds)
    python experiments/tools/noise_robustness.py --sigma 0.001 --mask-change 0 1 2 --out change.json
        (how far the masks move, apart from the metric: mask_change below)

The figures of experiments/fidelity-log.md "Noisy scans" before the plane refit was adopted for hybrid inference
were made with ``--refine-planes 0`` (then the default); today's default refits hybrid inference's planes.

Rows per (sigma, denoise): ``geometric`` (no model), ``learned`` and ``hybrid`` (the shipped model
unless --model); AP / AP50 / AP25 pooled over the scans of each --eval spec. The noise of scan i of
spec j comes from ``default_rng([seed, j, i, round(sigma * 1e6)])``, so every row sees the same noisy scans.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch
from scipy.spatial import cKDTree

from assist3d.data import open_dataset
from assist3d.bench.evaluation.ap import match_scene, summarize
from assist3d.core.fileio import write_json_atomic
from assist3d.learn.segmenter.checkpoint import load_segmenter
from assist3d.learn.segmenter.geometric import GeometricConfig, segment_geometric
from assist3d.learn.segmenter.hybrid import HYBRID_GEOMETRIC, segment_hybrid
from assist3d.learn.segmenter.infer import segment_points
from assist3d.learn.segmenter.shipped import shipped_model_path


def _local_planes(coord: np.ndarray, radius: float, cell: float, k: int):
    """The plane (PCA) fitted to the mean positions of the ``cell``-sized cells within ``radius`` of
    each cell of ``coord`` (N, 3) (at most the ``k`` nearest): ``(inverse (N,) cell of every point,
    centroid (V, 3), normal (V, 3), cells (V,) how many were fitted)``, float64."""
    grid = np.floor(coord.astype(np.float64) / cell).astype(np.int64)
    grid -= grid.min(0)
    _, inverse = np.unique(grid, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    v = int(inverse.max()) + 1
    counts = np.bincount(inverse, minlength=v).astype(np.float64)
    means = np.stack([np.bincount(inverse, weights=coord[:, c].astype(np.float64), minlength=v) for c in range(3)], 1)
    means /= counts[:, None]
    dist, idx = cKDTree(means).query(means, k=min(k, v), distance_upper_bound=radius)
    dist, idx = dist.reshape(v, -1), idx.reshape(v, -1)  # k = 1 (a single cell) gives 1-D arrays
    ok = np.isfinite(dist)  # (V, k); a cell is always its own nearest
    w = ok.astype(np.float64)
    nb = means[np.where(ok, idx, 0)]  # (V, k, 3)
    cells = w.sum(1)
    centroid = (nb * w[..., None]).sum(1) / cells[:, None]
    d = (nb - centroid[:, None, :]) * w[..., None]
    normal = np.linalg.eigh(np.einsum("vki,vkj->vij", d, d))[1][:, :, 0]  # smallest-eigenvalue eigenvector
    return inverse, centroid, normal, cells


def denoise_points(coord: np.ndarray, radius: float = 0.05, cell: float = 0.01, k: int = 32) -> np.ndarray:
    """(N, 3) float32 ``coord`` with each point moved onto the local surface: the plane fitted (PCA)
    to the mean positions of the ``cell``-sized cells within ``radius`` of its own cell (at most the
    ``k`` nearest), the point moved along that plane's normal only. One step of a moving-least-squares
    projection of degree one: it thins a surface that sensor noise spread over several voxel layers
    (raw fused depth, a LiDAR sweep) back towards one, as in the reconstructed meshes ScanNet's
    points come from, and rounds edges and small parts within about ``radius``. Cells, not points,
    are the neighbours, so the cost and the result depend little on the point density. Measured in
    experiments/fidelity-log.md ("Noisy scans"; not adopted). Deterministic."""
    coord = np.asarray(coord, np.float32)
    if len(coord) < 3:
        return coord.copy()
    inverse, centroid, normal, cells = _local_planes(coord, radius, cell, k)
    n_p, c_p = normal[inverse], centroid[inverse]
    off = np.einsum("ij,ij->i", coord.astype(np.float64) - c_p, n_p)
    off = np.where(cells[inverse] >= 3, off, 0.0)  # fewer than three cells around: no plane, the point stays
    return (coord.astype(np.float64) - off[:, None] * n_p).astype(np.float32)


def plane_refits(record: dict) -> dict[str, int]:
    """The plane refits of a result file of this script, per method (``geometric``, ``hybrid``): files
    written before --refine-planes existed were made without refits (0), and the first ones written with
    it hold one number for both methods."""
    refine = record.get("refine_planes", 0)
    return {"geometric": refine, "hybrid": refine} if isinstance(refine, int) else refine


def summarize_files(paths: list[Path]) -> None:
    """Mean ± sample std over noise seeds of every (sigma, denoise, method, plane refits, eval spec)
    AP50 and AP25. Files without AP rows (--mask-change results) are skipped with a note; plane refits
    as :func:`plane_refits` reads them."""
    import json
    import sys
    from collections import defaultdict

    cells: dict[tuple, list[tuple[int, float, float]]] = defaultdict(list)
    for p in paths:
        d = json.loads(Path(p).read_text())
        if "rows" not in d:
            print(f"{p}: no AP rows (a --mask-change result?), skipped", file=sys.stderr)
            continue
        refine = plane_refits(d)
        for row in d["rows"]:
            for j, spec in enumerate(d["eval"]):
                ref = refine.get(row["method"], "-")  # the learned rows use no planes
                key = (row["sigma"], row["denoise"], row["method"], j, Path(spec.split(":", 1)[-1]).name, ref)
                seed = d["seed"] if row["sigma"] > 0 else 0  # sigma 0 adds no noise: one value whatever the seed
                if all(s != seed for s, _, _ in cells[key]):
                    cells[key].append((seed, row[spec]["AP50"], row[spec]["AP25"]))
    print("| sigma (m) | denoise | method | plane refits | eval | AP50 mean ± std | AP25 mean ± std | noise seeds |")
    print("| ---: | --- | --- | ---: | --- | ---: | ---: | --- |")
    for key in sorted(cells, key=lambda k: (k[0], k[1], k[3], ("geometric", "learned", "hybrid").index(k[2]),
                                            str(k[5]))):
        vals = np.array([v for _, v, _ in cells[key]])
        ap25 = np.array([v for _, _, v in cells[key]])
        sd = (lambda x: f"{x.std(ddof=1):.3f}" if len(x) > 1 else "-")
        print(f"| {key[0]:g} | {'on' if key[1] else 'off'} | {key[2]} | {key[5]} | {key[4]} | "
              f"{vals.mean():.3f} ± {sd(vals)} | "
              f"{ap25.mean():.3f} ± {sd(ap25)} | {','.join(str(s) for s, _, _ in sorted(cells[key]))} |")


def mask_change(loaded, sets: list, sigma: float, seeds: list[int], method: str = "hybrid",
                geo: GeometricConfig = GeometricConfig(), hyb_geo: GeometricConfig = HYBRID_GEOMETRIC) -> dict:
    """How far the masks of ``method`` (hybrid, learned, geometric or superpoints: the superpoints as
    masks) move under noise, apart from the metric: per scan and draw, (a) each
    ground-truth object's best IoU with any predicted mask (objects of >= 100 valid points), clean and
    noisy, and how many cross IoU 0.5 either way; (b) each of the 20 highest-scored clean masks' best IoU
    with a noisy mask; (c) the share of score-order changes among pairs of clean masks matched both ways."""
    from assist3d.learn.segmenter.cluster import pairwise_iou
    from assist3d.learn.segmenter.infer import Segmentation
    from assist3d.learn.segmenter.superpoints import superpoints

    def run(coord: np.ndarray, color: np.ndarray | None) -> Segmentation:
        if method == "hybrid":
            return segment_hybrid(loaded.model, loaded.config, coord, color, geometric=hyb_geo)
        if method == "learned":
            return segment_points(loaded.model, loaded.config, coord, color)
        if method == "geometric":
            return segment_geometric(coord, geo)
        sp = superpoints(coord)  # superpoints as masks, the largest first
        sizes = np.bincount(sp)
        order = np.argsort(-sizes, kind="stable")
        masks = sp[None, :] == order[:, None]
        return Segmentation(masks=masks, scores=sizes[order].astype(np.float32), labels=sp)

    gt_delta, crossings, objects, agree, swapped, pairs = [], 0, 0, [], 0, 0
    for j, scans in enumerate(sets):
        for i, s in enumerate(scans):
            valid = s.valid if s.valid is not None else np.ones(len(s.coord), bool)
            ids, counts = np.unique(s.instance[valid & (s.instance >= 0)], return_counts=True)
            gt = np.stack([(s.instance == k) & valid for k in ids[counts >= 100]]) if (counts >= 100).any() else None
            clean = run(s.coord, s.color)
            for seed in seeds:
                rng = np.random.default_rng([seed, j, i, round(sigma * 1e6)])
                coord = (s.coord.astype(np.float64) + rng.normal(0.0, sigma, s.coord.shape)).astype(np.float32)
                noisy = run(coord, s.color)
                if gt is not None and len(clean.masks) and len(noisy.masks):
                    a = pairwise_iou(gt, clean.masks).max(1)
                    b = pairwise_iou(gt, noisy.masks).max(1)
                    gt_delta.extend(np.abs(a - b).tolist())
                    crossings += int(((a >= 0.5) != (b >= 0.5)).sum())
                    objects += len(a)
                top = clean.masks[:20]
                if len(top) and len(noisy.masks):
                    iou = pairwise_iou(top, noisy.masks)
                    agree.extend(iou.max(1).tolist())
                    match = iou.argmax(1)
                    ok = iou.max(1) >= 0.8
                    rank_clean = np.arange(len(top))[ok]
                    rank_noisy = match[ok]
                    for u in range(len(rank_clean)):
                        for v in range(u + 1, len(rank_clean)):
                            pairs += 1
                            swapped += int(rank_noisy[u] > rank_noisy[v])
    gt_delta_a, agree_a = np.array(gt_delta), np.array(agree)

    def stat(x: np.ndarray, f) -> float | None:  # None where no object or mask was compared
        return round(float(f(x)), 4) if len(x) else None
    return {"method": method, "refine_planes": (hyb_geo if method == "hybrid" else geo).refine, "sigma": sigma,
            "seeds": seeds, "objects": objects,
            "crossings_of_iou_0.5": crossings,
            "gt_best_iou_abs_change": {"median": stat(gt_delta_a, np.median),
                                       "p90": stat(gt_delta_a, lambda x: np.percentile(x, 90))},
            "top20_clean_mask_best_iou_with_noisy": {"median": stat(agree_a, np.median),
                                                     "share_below_0.8": stat(agree_a, lambda x: (x < 0.8).mean())},
            "score_order_swaps": {"pairs": pairs, "swapped": swapped}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sigma", type=float, nargs="+", default=[0.0, 0.0025, 0.005, 0.01])
    ap.add_argument("--denoise", type=int, nargs="+", default=[0], choices=[0, 1])
    ap.add_argument("--model", type=Path, default=None)
    ap.add_argument("--eval", action="append")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--out", type=Path)
    ap.add_argument("--summarize", type=Path, nargs="+", help="print the table of these result files and exit")
    ap.add_argument("--mask-change", type=int, nargs="+", metavar="SEED",
                    help="instead of AP rows: how far the masks move at the first --sigma for these noise seeds")
    ap.add_argument("--methods", nargs="+", default=["geometric", "learned", "hybrid"],
                    choices=["geometric", "learned", "hybrid"], help="the AP rows to compute")
    ap.add_argument("--refine-planes", type=int, default=None,
                    help="GeometricConfig.refine for both the geometric reference and hybrid inference (default: "
                         "each its own, 0 for the reference and HYBRID_GEOMETRIC's for hybrid inference)")
    ap.add_argument("--method", default="hybrid", choices=["hybrid", "learned", "geometric", "superpoints"],
                    help="whose masks --mask-change follows")
    args = ap.parse_args()
    if args.summarize:
        summarize_files(args.summarize)
        return
    if args.out is None:
        ap.error("--out is required (unless --summarize)")
    torch.set_num_threads(args.threads)
    here = Path(__file__).resolve().parents[2]
    specs = args.eval or [f"array:{here.parent / 'shared/data/real/dev'}",
                          f"array:{here.parent / 'shared/data/real/scannet_scene0451_01.npy'}"]
    model_path = args.model or shipped_model_path()
    loaded = load_segmenter(model_path)
    sets = [list(open_dataset(spec)) for spec in specs]
    geo = GeometricConfig() if args.refine_planes is None else GeometricConfig(refine=args.refine_planes)
    hyb_geo = HYBRID_GEOMETRIC if args.refine_planes is None else geo
    if args.mask_change:
        out = mask_change(loaded, sets, args.sigma[0], args.mask_change, args.method, geo, hyb_geo)
        print(out)
        write_json_atomic(args.out, {"model": str(model_path), "eval": specs, **out})
        return
    rows = []
    for sigma in args.sigma:
        for dn in args.denoise:
            matches: dict[str, list[list]] = {m: [[] for _ in specs] for m in args.methods}
            t0 = time.perf_counter()
            for j, scans in enumerate(sets):
                for i, s in enumerate(scans):
                    rng = np.random.default_rng([args.seed, j, i, round(sigma * 1e6)])
                    coord = (s.coord.astype(np.float64) + rng.normal(0.0, sigma, s.coord.shape)).astype(np.float32)
                    if dn:
                        coord = denoise_points(coord)
                    run = {"geometric": lambda: segment_geometric(coord, geo),
                           "learned": lambda: segment_points(loaded.model, loaded.config, coord, s.color),
                           "hybrid": lambda: segment_hybrid(loaded.model, loaded.config, coord, s.color,
                                                            geometric=hyb_geo)}
                    segs = {m: run[m]() for m in args.methods}
                    for m, seg in segs.items():
                        matches[m][j].append(match_scene(s.instance, seg.masks, seg.scores, valid=s.valid,
                                                         scene_id=s.scene_id))
            for m, per_spec in matches.items():
                row = {"sigma": sigma, "denoise": bool(dn), "method": m}
                for spec, ms in zip(specs, per_spec):
                    r = summarize(ms)
                    row[spec] = {k: round(float(r[k]), 4) for k in ("AP", "AP50", "AP25")}
                rows.append(row)
                print(f"sigma {sigma:.4f} denoise {dn} {m:9s} "
                      + "  ".join(f"AP50 {row[spec]['AP50']:.3f}" for spec in specs), flush=True)
            print(f"  ({time.perf_counter() - t0:.0f} s)", flush=True)
    write_json_atomic(args.out, {"model": str(model_path), "eval": specs, "seed": args.seed,
                                 "refine_planes": {"geometric": geo.refine, "hybrid": hyb_geo.refine}, "rows": rows})


if __name__ == "__main__":
    main()
