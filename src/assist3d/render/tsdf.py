"""ScanNet-like clouds (``point_source="tsdf"``): TSDF fusion of the rendered views, marching cubes,
mesh vertices.

ScanNet's points are the vertices of a mesh reconstructed by TSDF fusion and marching cubes, so
surfaces are smoothed, unobserved surfaces are missing and small loose pieces are deleted. This
module reproduces that on the views :func:`~assist3d.render.fusion.cast_and_fuse` casts anyway:

1. Integration (:class:`TsdfIntegrator`, one call per view in the thread that cast it). Every
   ``tsdf_stride``-th pixel in x and y with depth up to ``tsdf_max_depth`` marches its ray through
   the band ``range +- trunc`` (``trunc = tsdf_trunc + tsdf_trunc_per_m * depth``, ScanNet's rule)
   in steps of one voxel. A sample at ``range + off`` observes the projective signed distance
   ``-off`` (the hit's distance along the ray minus the sample's: positive in front of the surface,
   at most ``trunc`` behind it), normalised to ``-off / trunc``, in the voxel it falls in
   (scene-wide grid, :mod:`.voxel`); each voxel's value is the mean of its observations, weight 1
   each. The signs are those of the ray that made the sample, so voxels on the wrong side of a
   surface never get the wrong sign from a neighbouring pixel (a projective look-up of voxel
   centres does, at grazing angles). Sums are kept as integers (values quantised to 2**-20), so the
   means do not depend on the order views arrive in; sparse (sorted keys, merged with a stable
   sort), so memory follows the observed surface, not the room's volume.
2. Extraction: ``skimage.measure.marching_cubes`` at level 0 on dense slabs of the observed
   voxels' bounding box (at most 2**22 voxels each, welded at the shared layers), masked so that a
   cube is only meshed when all 8 corners were observed: no surface is invented where nothing was
   seen. Connected pieces smaller than ``tsdf_min_piece_m2`` are dropped.
3. Points: the surviving vertices, one per ``voxel_size`` voxel. Attributes come from the nearest
   *label hit*: one ray hit per half-TSDF-voxel cell over all integrated pixels of all views (the
   hits the surface was built from). The triangle and view of that hit then give instance,
   segment, colour and normal exactly as for ``point_source="render"``. Vertices farther than
   1.5 TSDF voxels from every hit are dropped, so no point exists away from a seen surface.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..config import RenderConfig
from ..core.contracts import Camera, SceneMesh
from ..core.errors import ConfigError
from .fusion import scene_grid
from .voxel import VoxelGrid, pick_one_per_voxel, pick_one_per_voxel_scan

log = logging.getLogger(__name__)

__all__ = ["TsdfIntegrator", "TsdfCloud", "require_marching_cubes", "tsdf_cloud", "HIT_RADIUS_VOXELS"]

QUANT = 1 << 20  # TSDF values in [-1, 1] are summed as integers of this scale (exact, order-free)
SLAB_VOXELS = 1 << 22  # largest dense array handed to marching cubes (16 MB of float32)
FLUSH_ROWS = 1 << 21  # pending rows before the sparse accumulators merge
HIT_RADIUS_VOXELS = 1.5  # vertices farther than this many TSDF voxels from every hit are dropped

MarchingCubes = Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]


def require_marching_cubes() -> MarchingCubes:
    """``skimage.measure.marching_cubes``, or a one-line :class:`ConfigError` when scikit-image is missing."""
    try:
        from skimage.measure import marching_cubes
    except ImportError:
        raise ConfigError("render.point_source='tsdf' needs scikit-image: pip install 'assist3d[sim]'") from None
    return marching_cubes


def _columns_along(center: np.ndarray, d: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(N, 3) float32 points ``center + t * d`` computed column by column."""
    pts = np.zeros((len(t), 3), np.float32)
    for j in range(3):
        col = d[:, j] * t
        col += center[j]
        pts[:, j] = col
    return pts


def _run_starts(keys: np.ndarray) -> np.ndarray:
    """Indices of the first element of each run of equal consecutive keys."""
    if len(keys) == 0:
        return np.zeros(0, np.int64)
    return np.flatnonzero(np.concatenate(([True], keys[1:] != keys[:-1])))


def _reduce_runs(keys: np.ndarray, q: np.ndarray, n: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sum q (int64) and n (int32; None = all ones) over runs of equal consecutive keys."""
    first = _run_starts(keys)
    if len(first) == 0:
        return keys, q, np.zeros(0, np.int32)
    if n is None:
        count = np.diff(np.append(first, len(keys))).astype(np.int32)
    else:
        count = np.add.reduceat(n, first)
    return keys[first], np.add.reduceat(q, first), count


def band_samples(grid: VoxelGrid, center: np.ndarray, d: np.ndarray, depth: np.ndarray, trunc: np.ndarray,
                 step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """TSDF observations of one view: (keys (V,) int64 sorted distinct, qsum (V,) int64, count (V,) int32).

    Every ray (world direction d (M, 3) float32 with camera z = 1, depth (M,) m, truncation (M,) m)
    is sampled every ``step`` m of its length from ``range - trunc`` to ``range + trunc``; a sample
    at ``range + off`` observes ``clip(-off / trunc, -1, 1)`` (positive in front of the surface) in
    the voxel it falls in, quantised to integers of scale ``QUANT``. Samples go offset by offset
    over all rays, so neighbouring rays in the same voxel form runs that are summed before the sort.
    """
    if len(depth) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int32)
    norm = np.sqrt(np.einsum("ij,ij->i", d, d))
    half = int(np.floor(float(trunc.max()) / step + 1e-6))
    parts = []
    for k in range(-half, half + 1):
        off = np.float32(k * step)
        act = np.flatnonzero(trunc >= abs(off) - 1e-6) if k else np.arange(len(depth))
        keys = grid.keys(_columns_along(center, d[act], depth[act] + off / norm[act]))
        q = np.rint(np.clip(-off / trunc[act], -1.0, 1.0) * np.float32(QUANT)).astype(np.int64)
        parts.append(_reduce_runs(keys, q, None))
    keys = np.concatenate([p[0] for p in parts])
    order = np.argsort(keys, kind="stable")
    return _reduce_runs(keys[order], np.concatenate([p[1] for p in parts])[order],
                        np.concatenate([p[2] for p in parts])[order])


class _SparseSum:
    """Per-voxel integer sums and counts over sorted distinct key batches, merged lazily."""

    def __init__(self) -> None:
        self.keys = np.zeros(0, np.int64)
        self.qsum = np.zeros(0, np.int64)
        self.weight = np.zeros(0, np.int32)
        self._pending: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self._rows = 0

    def add(self, keys: np.ndarray, qsum: np.ndarray, count: np.ndarray) -> None:
        self._pending.append((keys, qsum, count))
        self._rows += len(keys)
        if self._rows >= max(FLUSH_ROWS, len(self.keys)):
            self.flush()

    def flush(self) -> None:
        if not self._pending:
            return
        keys = np.concatenate([self.keys] + [p[0] for p in self._pending])
        qsum = np.concatenate([self.qsum] + [p[1] for p in self._pending])
        weight = np.concatenate([self.weight] + [p[2] for p in self._pending])
        self._pending, self._rows = [], 0
        order = np.argsort(keys, kind="stable")  # timsort: merges the already sorted runs
        self.keys, self.qsum, self.weight = _reduce_runs(keys[order], qsum[order], weight[order])


class _HitPool:
    """One ray hit per cell of a fine grid over all views, reduced lazily (like the fusion)."""

    def __init__(self, salt: int) -> None:
        self.salt = salt
        self.parts: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
        self._rows = 0
        self._kept = 0

    def add(self, keys: np.ndarray, coord: np.ndarray, face: np.ndarray, view: np.ndarray) -> None:
        self.parts.append((keys, coord, face, view))
        self._rows += len(keys)
        if self._rows - self._kept >= max(FLUSH_ROWS, self._kept):
            self.flush()

    def flush(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        cat = tuple(np.concatenate([p[i] for p in self.parts]) for i in range(4)) if self.parts else (
            np.zeros(0, np.int64), np.zeros((0, 3), np.float32), np.zeros(0, np.int32), np.zeros(0, np.int32))
        keep = pick_one_per_voxel(cat[0], self.salt)
        out = tuple(a[keep] for a in cat)
        self.parts = [out]
        self._rows = self._kept = len(keep)
        return out


@dataclass(frozen=True)
class _ViewPart:
    keys: np.ndarray
    qsum: np.ndarray
    count: np.ndarray
    hit_keys: np.ndarray
    hit_coord: np.ndarray
    hit_face: np.ndarray


@dataclass(frozen=True)
class TsdfVolume:
    """Observed voxels: keys (N,) int64 sorted, tsdf (N,) float32 in [-1, 1], weight (N,) int32 samples."""

    grid: VoxelGrid
    keys: np.ndarray
    tsdf: np.ndarray
    weight: np.ndarray


class TsdfIntegrator:
    """A :class:`~assist3d.render.fusion.ViewSink` integrating every view into a sparse TSDF and
    keeping the integrated hits for labelling (see module docs)."""

    def __init__(self, scene: SceneMesh, camera: Camera, cfg: RenderConfig, salt: int) -> None:
        reach = cfg.tsdf_trunc + cfg.tsdf_trunc_per_m * cfg.tsdf_max_depth  # widest band, m
        margin = int(np.ceil(reach / cfg.tsdf_voxel)) + 2  # so band samples are not clamped to the border
        self.grid = VoxelGrid.around(scene.vertices.min(axis=0), scene.vertices.max(axis=0), cfg.tsdf_voxel, margin)
        self.hit_grid = scene_grid(scene, cfg.tsdf_voxel / 2)
        s = cfg.tsdf_stride
        rows, cols = np.arange(0, camera.height, s), np.arange(0, camera.width, s)
        self.pix = (rows[:, None] * camera.width + cols[None, :]).reshape(-1)
        self.cfg = cfg
        self.salt = int(salt)
        self._sum = _SparseSum()
        self._hits = _HitPool(self.salt)

    def view(self, index: int, camera: Camera, t: np.ndarray, face: np.ndarray, dirs: np.ndarray) -> _ViewPart:
        cfg = self.cfg
        ts, fs = t[self.pix], face[self.pix]
        valid = (fs >= 0) & (ts > 0) & (ts <= np.float32(cfg.tsdf_max_depth))
        sel = np.flatnonzero(valid)
        center = camera.pose[:3, 3].astype(np.float32)
        d, dep = dirs[self.pix[sel]], ts[sel]
        trunc = np.float32(cfg.tsdf_trunc) + np.float32(cfg.tsdf_trunc_per_m) * dep
        keys, qsum, count = band_samples(self.grid, center, d, dep, trunc, cfg.tsdf_voxel)
        pts = _columns_along(center, d, dep)
        hk = self.hit_grid.keys(pts)
        pick = pick_one_per_voxel_scan(hk, (self.salt + 0x9E3779B97F4A7C15 * (index + 1)) & (2**62 - 1))
        return _ViewPart(keys, qsum, count, hk[pick], pts[pick], fs[sel][pick])

    def add(self, index: int, part: _ViewPart) -> None:
        self._sum.add(part.keys, part.qsum, part.count)
        self._hits.add(part.hit_keys, part.hit_coord, part.hit_face,
                       np.full(len(part.hit_keys), index, np.int32))

    def volume(self) -> TsdfVolume:
        self._sum.flush()
        s = self._sum
        tsdf = (s.qsum.astype(np.float64) / np.maximum(s.weight, 1) / QUANT).astype(np.float32)
        return TsdfVolume(self.grid, s.keys, tsdf, s.weight)

    def hits(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(coord (H, 3) float32, face (H,) int32, view (H,) int32) of the label hits."""
        _, coord, face, view = self._hits.flush()
        return coord, face, view


def _slab_surface(vol: np.ndarray, obs: np.ndarray, marching_cubes: MarchingCubes) -> tuple[np.ndarray, np.ndarray]:
    """Marching cubes of one dense slab, only in cubes whose 8 corners are observed."""
    empty = np.zeros((0, 3), np.float64), np.zeros((0, 3), np.int64)
    if min(vol.shape) < 2 or not (vol.min() <= 0.0 <= vol.max()):
        return empty
    cube = obs[:-1, :-1, :-1].copy()
    for a, b, c in ((1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0), (1, 0, 1), (0, 1, 1), (1, 1, 1)):
        cube &= obs[a:a + cube.shape[0], b:b + cube.shape[1], c:c + cube.shape[2]]
    if not cube.any():
        return empty
    mask = np.zeros(obs.shape, bool)
    mask[1:, 1:, 1:] = cube  # skimage's mask entry (i, j, k) enables the cube ending at (i, j, k)
    try:
        verts, faces, _, _ = marching_cubes(vol, 0.0, mask=mask)
    except RuntimeError:  # no surface in the enabled cubes
        return empty
    return verts.astype(np.float64), faces.astype(np.int64)


def weld(verts: np.ndarray, resolution: float = 1.0 / 4096) -> np.ndarray:
    """(V,) int64 representative (lowest index) of every vertex among those that coincide after
    rounding to ``resolution`` (units of ``verts``): marching cubes repeats a vertex on every edge
    that meets a corner lying exactly on the surface, and the slabs repeat their shared layer's
    vertices. ScanNet's cleaning likewise merges vertices closer than ~1 mm."""
    if not len(verts):
        return np.zeros(0, np.int64)
    q = np.rint(verts / resolution).astype(np.int64)
    order = np.lexsort((q[:, 2], q[:, 1], q[:, 0]))  # stable: lowest index first within a group
    qs = q[order]
    new = np.ones(len(q), bool)
    new[1:] = np.any(qs[1:] != qs[:-1], axis=1)
    group_first = order[new][np.cumsum(new) - 1]
    rep = np.empty(len(q), np.int64)
    rep[order] = group_first
    return rep


def marching_cubes_sparse(volume: TsdfVolume, marching_cubes: MarchingCubes) -> tuple[np.ndarray, np.ndarray]:
    """(verts (V, 3) float64 world, faces (F, 3) int64) of the zero level set of a sparse TSDF.

    Dense slabs along the grid's first axis over the observed bounding box of the other two;
    consecutive slabs share one voxel layer. Coinciding vertices are welded (:func:`weld`), so the
    mesh does not depend on where the slabs are cut.
    """
    empty = np.zeros((0, 3), np.float64), np.zeros((0, 3), np.int64)
    if len(volume.keys) < 8:
        return empty
    ijk = volume.grid.indices(volume.keys)  # keys sorted => ijk[:, 0] non-decreasing
    lo = ijk.min(axis=0)
    n1, n2 = (ijk[:, 1:].max(axis=0) - lo[1:] + 1).tolist()
    per_slab = max(2, SLAB_VOXELS // max(1, n1 * n2))
    verts, faces, nv = [], [], 0
    start, last = int(ijk[0, 0]), int(ijk[-1, 0])
    while start < last:
        end = min(start + per_slab - 1, last)
        r0, r1 = np.searchsorted(ijk[:, 0], [start, end + 1])
        sub = ijk[r0:r1] - [start, lo[1], lo[2]]
        vol = np.ones((end - start + 1, n1, n2), np.float32)
        obs = np.zeros(vol.shape, bool)
        vol[sub[:, 0], sub[:, 1], sub[:, 2]] = volume.tsdf[r0:r1]
        obs[sub[:, 0], sub[:, 1], sub[:, 2]] = True
        v, f = _slab_surface(vol, obs, marching_cubes)
        del vol, obs
        verts.append(v + [start, lo[1], lo[2]])
        faces.append(f + nv)
        nv += len(v)
        start = end
    v = np.concatenate(verts) if verts else empty[0]
    f = np.concatenate(faces) if faces else empty[1]
    f = weld(v)[f]
    return (v + volume.grid.lo) * volume.grid.size, f


def drop_small_pieces(verts: np.ndarray, faces: np.ndarray, min_area: float) -> tuple[np.ndarray, int, int]:
    """(keep (V,) bool, pieces, dropped pieces): vertices used by a face of a connected piece of at
    least ``min_area`` m^2 (vertices used by no face are never kept)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(verts)
    used = np.zeros(n, bool)
    used[faces.reshape(-1)] = True
    if not len(faces):
        return used, 0, 0
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]]])
    graph = coo_matrix((np.ones(len(e), np.int8), (e[:, 0], e[:, 1])), shape=(n, n))
    _, comp = connected_components(graph, directed=False)
    tri = verts[faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    labels, fcomp = np.unique(comp[faces[:, 0]], return_inverse=True)
    piece_area = np.bincount(fcomp.reshape(-1), weights=area, minlength=len(labels))
    big = np.zeros(int(comp.max()) + 1, bool)
    big[labels[piece_area >= min_area]] = True
    return used & big[comp], len(labels), int(np.count_nonzero(piece_area < min_area))


@dataclass(frozen=True)
class TsdfCloud:
    """Output vertices coord (N, 3) float32, sorted by ``voxel_size`` voxel; face (N,) int32 and
    view (N,) int32 of each one's nearest label hit; stats."""

    coord: np.ndarray
    face: np.ndarray
    view: np.ndarray
    stats: dict


def tsdf_cloud(scene: SceneMesh, integrator: TsdfIntegrator, cfg: RenderConfig, marching_cubes: MarchingCubes, *,
               salt: int) -> TsdfCloud:
    """Extract the surface of an integrated TSDF and turn its vertices into labelled points."""
    from scipy.spatial import cKDTree

    volume = integrator.volume()
    verts, faces = marching_cubes_sparse(volume, marching_cubes)
    keep, pieces, dropped = drop_small_pieces(verts, faces, cfg.tsdf_min_piece_m2)
    pts = verts[keep].astype(np.float32)
    pts = pts[pick_one_per_voxel(scene_grid(scene, cfg.voxel_size).keys(pts), salt)]
    hit_coord, hit_face, hit_view = integrator.hits()
    if len(hit_coord) and len(pts):
        _, j = cKDTree(hit_coord).query(pts, distance_upper_bound=HIT_RADIUS_VOXELS * cfg.tsdf_voxel)
        near = np.flatnonzero(j < len(hit_coord))
    else:
        j, near = np.zeros(len(pts), np.int64), np.zeros(0, np.int64)
    stats = {"tsdf_voxels": len(volume.keys), "label_hits": len(hit_coord), "mesh_vertices": int(np.count_nonzero(
        np.bincount(faces.reshape(-1), minlength=len(verts)))), "mesh_faces": len(faces), "mesh_pieces": pieces,
        "mesh_pieces_dropped": dropped, "mesh_vertices_kept": int(np.count_nonzero(keep)),
        "far_from_hits_dropped": len(pts) - len(near)}
    log.debug("tsdf: %s", stats)
    jn = j[near]
    return TsdfCloud(pts[near], hit_face[jn].astype(np.int32), hit_view[jn].astype(np.int32), stats)
