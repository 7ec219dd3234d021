"""Upper bound of a 'coplanar flat tile' for the default render: a tile counts as flat when its four corner rays hit
triangles of one edge-connected group of coplanar triangles with equal instance, segment and colour (no convexity
check, so this over-counts what a correct version could save). Patches cast_adaptive's flatness test in memory and
renders 3 scenes both ways, one thread, from the same vantage points.
   .venv/bin/python experiments/speed-leads-2026-12-07/coplanar.py"""
import sys
import time
from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

sys.path.insert(0, str(Path(__file__).parent))
import assist3d.render.budget as B  # noqa: E402
import assist3d.render.fusion as Fu  # noqa: E402
from assist3d.render.camera import vantage_cameras  # noqa: E402
from assist3d.render.raycast import make_caster  # noqa: E402
from assist3d.render.vantage import select_vantage_points  # noqa: E402
from scenes import rendered_scenes  # noqa: E402


def coplanar_groups(scene) -> np.ndarray:
    v, f = scene.vertices.astype(np.float64), scene.faces
    _, vid = np.unique(np.round(v / 1e-5).astype(np.int64), axis=0, return_inverse=True)
    fv = vid.ravel()[f]  # welded vertex ids
    e = np.sort(np.concatenate([fv[:, [0, 1]], fv[:, [1, 2]], fv[:, [2, 0]]]), axis=1)
    fid = np.tile(np.arange(len(f)), 3)
    key = e[:, 0] * (int(fv.max()) + 1) + e[:, 1]
    o = np.argsort(key, kind="stable")
    same = np.flatnonzero(key[o][1:] == key[o][:-1])
    a, b = fid[o][same], fid[o][same + 1]
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    ln = np.linalg.norm(n, axis=1)
    un = n / np.maximum(ln, 1e-30)[:, None]
    off = np.einsum("ij,ij->i", un, tri[:, 0])
    ok = (np.einsum("ij,ij->i", un[a], un[b]) > 1 - 1e-9) & (np.abs(off[a] - off[b]) < 1e-6) & (ln[a] > 0) & (ln[b] > 0)
    ok &= (scene.face_instance[a] == scene.face_instance[b]) & (scene.face_segment[a] == scene.face_segment[b])
    ok &= np.all(scene.face_colors[a] == scene.face_colors[b], axis=1)
    g = coo_matrix((np.ones(int(ok.sum())), (a[ok], b[ok])), shape=(len(f), len(f)))
    return connected_components(g, directed=False)[1]


def main() -> None:
    import inspect
    src = inspect.getsource(B.cast_adaptive)
    old = "        flat = active & (f00 >= 0) & (f00 == lat[1:, :-1]) & (f00 == lat[:-1, 1:]) & (f00 == lat[1:, 1:])\n"
    new = ("        gl = np.take(GROUP, lat, mode='clip') if GROUP is not None else lat\n"
           "        g00 = gl[:-1, :-1]\n"
           "        flat = active & (f00 >= 0) & (g00 == gl[1:, :-1]) & (g00 == gl[:-1, 1:]) & (g00 == gl[1:, 1:])\n")
    assert src.count(old) == 1, "cast_adaptive changed: update this script"
    ns = dict(vars(B))
    exec(compile(src.replace(old, new), B.__file__, "exec"), ns)
    patched = ns["cast_adaptive"]
    for scene, room, cfg in rendered_scenes(3):
        comp = coplanar_groups(scene)
        cams = vantage_cameras(select_vantage_points(scene, room, cfg, rng=np.random.default_rng(0)), cfg)
        cfg1 = cfg.model_copy(update={"threads": 1})
        res = {}
        for mode in ("default", "coplanar", "default", "coplanar"):  # in turn, the second of each counts
            ns["GROUP"] = None if mode == "default" else np.concatenate([comp, comp.max() + 1 + np.arange(12)])
            Fu.cast_adaptive = B.cast_adaptive if mode == "default" else patched
            caster = make_caster(cfg.backend, scene.vertices, scene.faces)
            t0 = time.perf_counter()
            h = Fu.cast_and_fuse(scene, caster, cams, cfg1, rng=np.random.default_rng(5))
            res[mode] = (h, time.perf_counter() - t0)
        Fu.cast_adaptive = B.cast_adaptive
        (hb, tb), (hg, tg) = res["default"], res["coplanar"]
        grid = Fu.scene_grid(scene, cfg.voxel_size)
        kb, kg = grid.keys(hb.coord), grid.keys(hg.coord)
        common, ib, ig = np.intersect1d(kb, kg, return_indices=True)
        lab = scene.face_instance
        print(f"triangles {len(scene.faces)}, groups {comp.max() + 1}; rays {hb.rays_cast} -> {hg.rays_cast} "
              f"({hg.rays_cast / hb.rays_cast:.3f}); cast_and_fuse s {tb:.2f} -> {tg:.2f}; "
              f"voxels kept {len(common) / len(kb):.5f}; labels equal {np.mean(lab[hb.face[ib]] == lab[hg.face[ig]]):.5f}")


main()
