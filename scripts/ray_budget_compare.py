"""Is the adaptive ray budget's cloud the full render's cloud? Voxel coverage and label agreement.

For scenes 0..N-1 of a dataset (preset assist3d unless --config, seed --seed), lays the scene out
once and fuses it twice, with ``render.rays = full`` (the reference: one ray per pixel) and with
``render.rays = adaptive``, from the same generator state. Both clouds hold one point per occupied
2 cm voxel; per scene it prints

* coverage: the share of the reference's occupied voxels that the adaptive cloud also occupies,
* extra: adaptive voxels the reference does not occupy, as a share of the reference's voxels,
* label agreement: the share of the shared voxels whose points carry the same instance id (and
  the same for colour),
* points of each cloud, and per instance the ratio of adaptive to reference points (its
  distribution over all instances of all scenes), instances that lost every point,
* rays cast by each.

    python scripts/ray_budget_compare.py --scenes 20 [--ray-tile 8] [--json out.json]

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
from assist3d.render.fusion import scene_grid
from assist3d.render.raycast import make_caster
from assist3d.scene.assemble import assemble_scene
from assist3d.scene.layout import build_layout


def compare_clouds(ref, fast, grid) -> dict:
    """Voxel-level comparison of two one-point-per-voxel clouds (PointSample) on ``grid``."""
    kr, kf = grid.keys(ref.coord), grid.keys(fast.coord)
    common, ir, jf = np.intersect1d(kr, kf, assume_unique=True, return_indices=True)
    same_inst = ref.instance[ir] == fast.instance[jf]
    same_color = np.all(ref.color[ir] == fast.color[jf], axis=1)
    n_inst = int(max(ref.instance.max(initial=-1), fast.instance.max(initial=-1))) + 1
    pr = np.bincount(ref.instance[ref.instance >= 0], minlength=n_inst)
    pf = np.bincount(fast.instance[fast.instance >= 0], minlength=n_inst)
    seen = pr > 0
    return {
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
    ap.add_argument("--ray-tile", type=int, default=None, help="render.ray_tile of the adaptive render")
    ap.add_argument("--json", default=None, help="write per-scene results here")
    args = ap.parse_args()
    cfg = load_config(args.config, {"seed": args.seed})
    full = cfg.render.model_copy(update={"rays": "full"})
    upd = {"rays": "adaptive"} | ({"ray_tile": args.ray_tile} if args.ray_tile else {})
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
        row = compare_clouds(out["ref"].sample, out["fast"].sample, scene_grid(mesh, cfg.render.voxel_size))
        ratios += row.pop("instance_ratio")
        row.update(scene=k, rays_ref=out["ref"].stats["rays"], rays_fast=out["fast"].stats["rays_cast"],
                   seconds_ref=round(out["ref_s"], 3), seconds_fast=round(out["fast_s"], 3),
                   cpu_ref=round(out["ref_cpu"], 3), cpu_fast=round(out["fast_cpu"], 3))
        rows.append(row)
        print(f"scene {k:3d}: coverage {row['coverage']:.5f} extra {row['extra']:.5f} "
              f"labels {row['label_agreement']:.5f} colours {row['color_agreement']:.5f} "
              f"points {row['voxels_ref']} -> {row['voxels_fast']} instances lost {row['instances_lost']}/"
              f"{row['instances_ref']} rays {row['rays_ref']} -> {row['rays_fast']} "
              f"({row['rays_fast'] / row['rays_ref']:.3f}) cpu s {row['cpu_ref']} -> {row['cpu_fast']}", flush=True)
    r = np.asarray(ratios)
    summary = {"scenes": len(rows), "ray_tile": fast.ray_tile}
    for key in ("coverage", "extra", "label_agreement", "color_agreement", "voxels_ref", "voxels_fast", "cpu_ref",
                "cpu_fast"):
        v = np.asarray([row[key] for row in rows], np.float64)
        summary[key] = {"min": float(v.min()), "mean": float(v.mean()), "max": float(v.max())}
    summary["rays_share"] = float(sum(x["rays_fast"] for x in rows) / sum(x["rays_ref"] for x in rows))
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
