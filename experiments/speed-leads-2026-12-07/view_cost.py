"""Where one view's CPU goes in the default render (`render.rays: adaptive`), one thread, 2 scenes x 60 views.
   .venv/bin/python experiments/speed-leads-2026-12-07/view_cost.py"""
import collections
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import assist3d.render.budget as B  # noqa: E402
import assist3d.render.voxel as V  # noqa: E402
from assist3d.render.camera import pixel_directions, rotate_directions, vantage_cameras  # noqa: E402
from assist3d.render.fusion import scene_grid  # noqa: E402
from assist3d.render.raycast import make_caster  # noqa: E402
from assist3d.render.vantage import select_vantage_points  # noqa: E402
from scenes import rendered_scenes  # noqa: E402

T: collections.Counter = collections.Counter()


def timed(name, f):
    def w(*a, **k):
        t = time.perf_counter()
        r = f(*a, **k)
        T[name] += time.perf_counter() - t
        return r
    return w


B._occluders = timed("slender-part occluders", B._occluders)
B._bar_images = timed("slender-part images", B._bar_images)


class Timed:
    def __init__(self, c, name):
        self.c, self.name = c, name

    def cast(self, o, d):
        t = time.perf_counter()
        r = self.c.cast(o, d)
        T[self.name] += time.perf_counter() - t
        T[self.name + " rays"] += len(o)
        return r


views = 0
for scene, room, cfg in rendered_scenes(2):
    cams = vantage_cameras(select_vantage_points(scene, room, cfg, rng=np.random.default_rng(0)), cfg)
    caster = Timed(make_caster(cfg.backend, scene.vertices, scene.faces), "embree")
    planes = B.face_planes(scene, sky=True)
    sky = Timed(make_caster(cfg.backend, *B.sky_box(scene)), "embree (sky box)")
    c0 = cams[0]
    cam_dirs = pixel_directions(c0.width, c0.height, c0.fx, c0.fy, c0.cx, c0.cy).astype(np.float32)
    grid = scene_grid(scene, cfg.voxel_size)
    n_ids = int(scene.face_instance.max(initial=-1)) + 2
    inst_of_face = np.append((scene.face_instance + 1).astype(np.int32), np.int32(n_ids))
    for cam in cams:  # the steps of fusion.cast_and_fuse's one_view, timed one by one
        views += 1
        t0 = time.perf_counter()
        dirs = rotate_directions(cam_dirs, cam.pose)
        center = cam.pose[:3, 3].astype(np.float32)
        t1 = time.perf_counter()
        t, face, _ = B.cast_adaptive(caster, planes, cam, dirs, cfg.ray_tile, sky, None)
        t2 = time.perf_counter()
        pix = np.flatnonzero(face >= 0)
        np.bincount(np.take(inst_of_face, face), minlength=n_ids + 1)
        tp = np.take(t, pix)
        cols = []
        for j in range(3):
            col = np.take(dirs[:, j], pix)
            col *= tp
            col += center[j]
            cols.append(col)
        t3 = time.perf_counter()
        keys = grid.keys_of_columns(cols)
        keep = V.pick_one_per_voxel_scan(keys, 12345)
        t4 = time.perf_counter()
        T["rotate directions"] += t1 - t0
        T["cast_adaptive (all)"] += t2 - t1
        T["hit points"] += t3 - t2
        T["voxel keys + per-view pick"] += t4 - t3
        T["hits"] += len(pix)
inner = sum(T[k] for k in ("embree", "embree (sky box)", "slender-part occluders", "slender-part images"))
T["cast_adaptive: its own numpy"] = T["cast_adaptive (all)"] - inner
for k, v in T.items():
    unit = "per view" if k.endswith("rays") or k == "hits" else "ms per view"
    print(f"{k:32s} {v / views * (1 if unit == 'per view' else 1e3):10.2f} {unit}")
