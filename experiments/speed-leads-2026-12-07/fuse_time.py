"""One-thread `cast_and_fuse` of the first 3 default scenes (seed 0), the minimum of REPS runs each, and a digest of
what it returns (to check that a change is bit-identical). Lead 1 ran it with and without `casting.patch`, in turn:
   .venv/bin/python experiments/speed-leads-2026-12-07/fuse_time.py [REPS]"""
import hashlib
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import assist3d.render.fusion as Fu  # noqa: E402
from assist3d.render.camera import vantage_cameras  # noqa: E402
from assist3d.render.raycast import make_caster  # noqa: E402
from assist3d.render.vantage import select_vantage_points  # noqa: E402
from scenes import rendered_scenes  # noqa: E402

reps = int(sys.argv[1]) if len(sys.argv) > 1 else 3
total = 0.0
digest = hashlib.blake2b(digest_size=8)
for scene, room, cfg in rendered_scenes(3):
    cfg1 = cfg.model_copy(update={"threads": 1})
    cams = vantage_cameras(select_vantage_points(scene, room, cfg1, rng=np.random.default_rng(0)), cfg1)
    caster = make_caster(cfg1.backend, scene.vertices, scene.faces)
    best = float("inf")
    for _ in range(reps):
        t0 = time.perf_counter()
        out = Fu.cast_and_fuse(scene, caster, cams, cfg1, rng=np.random.default_rng(7))
        best = min(best, time.perf_counter() - t0)
    total += best
    for a in (out.coord, out.face, out.view, out.pixel_counts):
        digest.update(np.ascontiguousarray(a).tobytes())
print(f"cast_and_fuse, one thread, minimum of {reps}: {total:.3f} s for 3 scenes; digest {digest.hexdigest()}")
