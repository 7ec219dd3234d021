"""Embree with and without RTC_SCENE_FLAG_ROBUST (embreex's `robust` argument; the renderer uses robust): ns a ray
over 12 full views of scene 1 of the default render, and what the rays that differ hit.
   .venv/bin/python experiments/speed-leads-2026-12-07/embree_robust.py"""
import sys
import time
from pathlib import Path

import numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

sys.path.insert(0, str(Path(__file__).parent))
from assist3d.render.camera import pixel_directions, rotate_directions, vantage_cameras  # noqa: E402
from assist3d.render.vantage import select_vantage_points  # noqa: E402
from scenes import rendered_scenes  # noqa: E402

scene, room, cfg = rendered_scenes(2)[1]
cams = vantage_cameras(select_vantage_points(scene, room, cfg, rng=np.random.default_rng(0)), cfg)
c0 = cams[0]
cd = pixel_directions(c0.width, c0.height, c0.fx, c0.fy, c0.cx, c0.cy).astype(np.float32)
views = [(np.broadcast_to(c.pose[:3, 3].astype(np.float32), cd.shape).copy(), rotate_directions(cd, c.pose))
         for c in cams[:12]]
n = sum(len(o) for o, _ in views)
bvh = {}
for robust in (True, False, True, False):
    s = rtcore_scene.EmbreeScene(robust=robust)
    bvh[robust] = (s, TriangleMesh(s, np.ascontiguousarray(scene.vertices, np.float32),
                                   np.ascontiguousarray(scene.faces, np.int32)))
    s.run(views[0][0][:10], views[0][1][:10])
    t0 = time.perf_counter()
    for o, d in views:
        s.run(o, d, output=1)
    print(f"robust={robust}: {(time.perf_counter() - t0) / n * 1e9:.1f} ns a ray ({n} rays)")
cats = dict.fromkeys(["same instance", "other instance, depth within 1 cm", "other instance, depth jump",
                      "robust hit, fast miss", "robust miss, fast hit"], 0)
for o, d in views:
    a, b = bvh[True][0].run(o, d, output=1), bvh[False][0].run(o, d, output=1)
    for i in np.flatnonzero(a["primID"] != b["primID"]):
        fa, fb = a["primID"][i], b["primID"][i]
        if fa < 0 or fb < 0:
            cats["robust miss, fast hit" if fa < 0 else "robust hit, fast miss"] += 1
        elif scene.face_instance[fa] == scene.face_instance[fb]:
            cats["same instance"] += 1
        else:
            cats["other instance, depth within 1 cm" if abs(a["tfar"][i] - b["tfar"][i]) < 0.01
                 else "other instance, depth jump"] += 1
print("rays whose triangle differs:", cats)
