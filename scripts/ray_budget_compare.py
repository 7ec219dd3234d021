"""Is a ray budget's cloud the full render's cloud? Voxel coverage and label agreement.

For scenes 0..N-1 of a dataset (preset assist3d unless --config, seed --seed), lays the scene out
once and fuses it twice, with ``render.rays = full`` (the reference: one ray per pixel) and with
``render.rays = adaptive`` (or ``--rays footprint``), from the same generator state. Both clouds hold one point per occupied
2 cm voxel; per scene it prints

* coverage: the share of the reference's occupied voxels that the adaptive cloud also occupies,
* extra: adaptive voxels the reference does not occupy, as a share of the reference's voxels,
* label agreement: the share of the shared voxels whose points carry the same instance id (and
  the same for colour); where a voxel holds hits of two instances (an object on the floor), each
  render's pseudo-random pick keeps either, so two renders of different rays disagree there by chance,
* correct labels: the share of the fast cloud's points whose instance id is one that the reference's
  rays hit in that voxel (from the reference's raw hits, cast once more), and the share of the
  reference's voxels that hold hits of two or more labels (mixed),
* points of each cloud, and per instance the ratio of adaptive to reference points (its
  distribution over all instances of all scenes), instances that lost every point,
* rays cast by each.

    python scripts/ray_budget_compare.py --scenes 20 [--rays footprint] [--ray-spacing 0.5] [--ray-tile 8] [--json out.json]

CPU seconds of each render (all threads) are printed too: rough, and not a benchmark.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from assist3d.assets import open_catalog_for
from assist3d.config import load_config
from assist3d.core.rng import make_rng, scene_seed
from assist3d.pipeline.scene import scene_classes
from assist3d.render import render_point_cloud
from assist3d.render.camera import vantage_cameras
from assist3d.render.fusion import cast_and_fuse, scene_grid
from assist3d.render.raycast import make_caster
from assist3d.scene.assemble import assemble_scene
from assist3d.scene.layout import build_layout


class HitLabels:
    """A view sink (``cast_and_fuse``) that keeps, over all views, every distinct (voxel, label) pair of the
    raw hits: ``pairs`` (M,) int64 sorted, key * (instances + 1) + instance + 1."""

    def __init__(self, scene, grid):
        self.grid, self.face_instance = grid, scene.face_instance
        self.n = int(scene.face_instance.max(initial=-1)) + 2
        self.parts: list[np.ndarray] = []

    def view(self, index, camera, t, face, dirs):
        hit = np.flatnonzero(face >= 0)
        pts = camera.pose[:3, 3].astype(np.float32) + t[hit, None] * dirs[hit]
        return np.unique(self.grid.keys(pts) * self.n + self.face_instance[face[hit]] + 1)

    def add(self, index, part):
        self.parts.append(part)

    @property
    def pairs(self) -> np.ndarray:
        return np.unique(np.concatenate(self.parts)) if self.parts else np.zeros(0, np.int64)


def compare_clouds(ref, fast, grid, pairs: np.ndarray | None = None, n_labels: int = 0) -> dict:
    """Voxel-level comparison of two one-point-per-voxel clouds (PointSample) on ``grid``; with the reference
    render's raw (voxel, label) ``pairs`` (:class:`HitLabels`) also whether each fast point's label is one the
    reference's rays saw in its voxel (correct), and how many reference voxels hold hits of two labels."""
    kr, kf = grid.keys(ref.coord), grid.keys(fast.coord)
    common, ir, jf = np.intersect1d(kr, kf, assume_unique=True, return_indices=True)
    same_inst = ref.instance[ir] == fast.instance[jf]
    same_color = np.all(ref.color[ir] == fast.color[jf], axis=1)
    n_inst = int(max(ref.instance.max(initial=-1), fast.instance.max(initial=-1))) + 1
    pr = np.bincount(ref.instance[ref.instance >= 0], minlength=n_inst)
    pf = np.bincount(fast.instance[fast.instance >= 0], minlength=n_inst)
    seen = pr > 0
    extra = {}
    if pairs is not None:
        valid = np.isin(kf * n_labels + fast.instance + 1, pairs)
        vox = pairs // n_labels
        extra = {"label_valid": float(valid.mean()) if len(valid) else 1.0,
                 "mixed_voxels": float(np.count_nonzero(vox[1:] == vox[:-1]) / max(len(np.unique(vox)), 1))}
    return extra | {
        "voxels_ref": int(len(kr)), "voxels_fast": int(len(kf)), "common": int(len(common)),
        "coverage": len(common) / max(len(kr), 1),
        "extra": (len(kf) - len(common)) / max(len(kr), 1),
        "label_agreement": float(same_inst.mean()) if len(common) else 1.0,
        "color_agreement": float(same_color.mean()) if len(common) else 1.0,
        "instances_ref": int(seen.sum()), "instances_lost": int(np.count_nonzero(seen & (pf == 0))),
        "instance_ratio": (pf[seen] / pr[seen]).tolist(),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--config", default=None, help="a generate config file (default: the built-in defaults)")
    ap.add_argument("--ray-tile", type=int, default=None, help="render.ray_tile of the fast render")
    ap.add_argument("--rays", default="adaptive", choices=["adaptive", "footprint"], help="the fast render's render.rays")
    ap.add_argument("--ray-spacing", type=float, default=None, help="render.ray_spacing (rays footprint), voxels")
    ap.add_argument("--json", default=None, help="write per-scene results here")
    args = ap.parse_args()
    cfg = load_config(args.config, {"seed": args.seed})
    full = cfg.render.model_copy(update={"rays": "full"})
    upd = ({"rays": args.rays} | ({"ray_tile": args.ray_tile} if args.ray_tile else {})
           | ({"ray_spacing": args.ray_spacing} if args.ray_spacing else {}))
    fast = cfg.render.model_copy(update=upd)
    fast = type(fast).model_validate(fast.model_dump())
    catalog = open_catalog_for(cfg.assets)
    classes = scene_classes(catalog, cfg)
    rows = []
    ratios: list[float] = []
    for k in range(args.scenes):
        seed = scene_seed(cfg.seed, k)
        layout = build_layout(catalog, cfg, seed, scene_index=k)
        mesh = assemble_scene(layout, catalog, classes)
        caster = make_caster(cfg.render.backend, mesh.vertices, mesh.faces)
        out = {}
        for name, rc in (("ref", full), ("fast", fast)):
            t0, c0 = time.perf_counter(), time.process_time()
            out[name] = render_point_cloud(mesh, layout.room, rc, rng=make_rng(seed, "render"), caster=caster)
            out[name + "_s"] = time.perf_counter() - t0
            out[name + "_cpu"] = time.process_time() - c0
        grid = scene_grid(mesh, cfg.render.voxel_size)
        labels = HitLabels(mesh, grid)  # the full render's rays again, every (voxel, label) they hit
        cams = vantage_cameras(out["ref"].centers, full)
        cast_and_fuse(mesh, caster, cams, full, rng=make_rng(seed, "labels"), sink=labels)
        row = compare_clouds(out["ref"].sample, out["fast"].sample, grid, labels.pairs, labels.n)
        ratios += row.pop("instance_ratio")
        row.update(scene=k, rays_ref=out["ref"].stats["rays"], rays_fast=out["fast"].stats["rays_cast"],
                   hits_ref=out["ref"].stats["raw_hits"], hits_fast=out["fast"].stats["raw_hits"],
                   seconds_ref=round(out["ref_s"], 3), seconds_fast=round(out["fast_s"], 3),
                   cpu_ref=round(out["ref_cpu"], 3), cpu_fast=round(out["fast_cpu"], 3))
        rows.append(row)
        print(f"scene {k:3d}: coverage {row['coverage']:.5f} extra {row['extra']:.5f} "
              f"labels {row['label_agreement']:.5f} correct {row['label_valid']:.5f} mixed {row['mixed_voxels']:.4f} colours {row['color_agreement']:.5f} "
              f"points {row['voxels_ref']} -> {row['voxels_fast']} instances lost {row['instances_lost']}/"
              f"{row['instances_ref']} rays {row['rays_ref']} -> {row['rays_fast']} "
              f"({row['rays_fast'] / row['rays_ref']:.3f}) hits {row['hits_ref']} -> {row['hits_fast']} cpu s {row['cpu_ref']} -> {row['cpu_fast']}", flush=True)
    r = np.asarray(ratios)
    summary = {"scenes": len(rows), "rays": fast.rays, "ray_tile": fast.ray_tile}
    if fast.rays == "footprint":
        summary["ray_spacing"] = fast.ray_spacing
    for key in ("coverage", "extra", "label_agreement", "label_valid", "mixed_voxels", "color_agreement", "voxels_ref", "voxels_fast", "cpu_ref",
                "cpu_fast"):
        v = np.asarray([row[key] for row in rows], np.float64)
        summary[key] = {"min": float(v.min()), "mean": float(v.mean()), "max": float(v.max())}
    summary["rays_share"] = float(sum(x["rays_fast"] for x in rows) / sum(x["rays_ref"] for x in rows))
    summary["hits_share"] = float(sum(x["hits_fast"] for x in rows) / sum(x["hits_ref"] for x in rows))
    summary["instances_lost"] = int(sum(x["instances_lost"] for x in rows))
    summary["instances"] = int(sum(x["instances_ref"] for x in rows))
    summary["instance_ratio"] = {q: float(np.quantile(r, p)) for q, p in
                                 (("min", 0), ("p01", 0.01), ("p05", 0.05), ("median", 0.5), ("p95", 0.95),
                                  ("max", 1))} if len(r) else {}
    print(json.dumps(summary, indent=1))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"summary": summary, "scenes": rows}, f, indent=1)


if __name__ == "__main__":
    main()
