# Counts, for issue 52, the tiles of the ray budget whose corners hit distinct but coplanar triangles of one
# instance (docs/generation.md, "A lead measured and not taken"). Run from the repository root:
#   .venv/bin/python experiments/raybudget-coplanar-2026-12-06/count.py
# Printed 2026-12-06 (2 default scenes, seed 0): rays 8447629, non-flat tiles {8: 154113, 4: 408056, 2: 1021922},
# of them coplanar {8: 34757, 4: 104570, 2: 295263}.
"""How many rays would a 'coplanar corners' flatness save? Re-runs cast_adaptive's levels and, per level,
counts non-flat tiles whose 4 corner faces are distinct but lie in one plane with one instance."""
import numpy as np
from assist3d.config import parse_config
from assist3d.pipeline.scene import SceneGenerator, SceneJob
import assist3d.render.budget as B
import assist3d.render.fusion as F

stats = {"rays": 0, "single": 0, "tiles_nonflat": {8: 0, 4: 0, 2: 0}, "tiles_coplanar": {8: 0, 4: 0, 2: 0}}
orig = B.cast_adaptive
SCENE = {}

def wrapped(caster, planes, camera, dirs, tile, sky=None):
    t, face, n = orig(caster, planes, camera, dirs, tile, sky)
    stats["rays"] += n
    # classify tiles at each level using the full result (face of every pixel)
    W, H = camera.width, camera.height
    img = face.reshape(H, W)
    nrm = planes.normal / np.linalg.norm(planes.normal, axis=1, keepdims=True).clip(1e-30)
    off = planes.offset / np.linalg.norm(planes.normal, axis=1).clip(1e-30)
    inst = SCENE["inst"]
    for s in (8, 4, 2):
        rows, cols = B.lattice(H, s), B.lattice(W, s)
        lat = img[np.ix_(rows, cols)]
        c = [lat[:-1, :-1], lat[1:, :-1], lat[:-1, 1:], lat[1:, 1:]]
        hit = (c[0] >= 0) & (c[1] >= 0) & (c[2] >= 0) & (c[3] >= 0) & (c[0] < len(inst)) & (c[1] < len(inst)) & (c[2] < len(inst)) & (c[3] < len(inst))
        nonflat = ~((c[0] == c[1]) & (c[0] == c[2]) & (c[0] == c[3]))
        stats["tiles_nonflat"][s] += int((nonflat).sum())
        sel = hit & nonflat
        f = [x[sel] for x in c]
        same = np.ones(len(f[0]), bool)
        for k in (1, 2, 3):
            same &= (np.abs(np.einsum("ij,ij->i", nrm[f[0]], nrm[f[k]])) > 1 - 1e-6)
            same &= np.abs(np.abs(off[f[0]]) - np.abs(off[f[k]])) < 1e-4
            same &= inst[f[0]] == inst[f[k]]
        stats["tiles_coplanar"][s] += int(same.sum())
    return t, face, n

B.cast_adaptive = wrapped
F.cast_adaptive = wrapped
cfg = parse_config({"seed": 0, "render": {"threads": 1}})
gen = SceneGenerator(cfg)
import tempfile, assist3d.render as R
orig_render = R.render_point_cloud
def rpc(scene, room, cfg, **kw):
    SCENE["inst"] = scene.face_instance
    return orig_render(scene, room, cfg, **kw)
import assist3d.pipeline.scene as PS
if hasattr(PS, "render_point_cloud"): PS.render_point_cloud = rpc
R.render_point_cloud = rpc
with tempfile.TemporaryDirectory() as tmp:
    for i in range(2):
        gen.scene(SceneJob(i, tmp))
print(stats)
