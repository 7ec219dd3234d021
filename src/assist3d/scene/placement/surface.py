"""Where a support's *mesh* really carries objects: a height map of each support surface.

A ``SupportSurface`` record says "objects can stand at height h inside this polygon"; catalog
meshes do not always agree (bevelled table tops, cushions above the seat board, a polygon that
overhangs the model). Before placing on a surface, the surface is sampled on a 2 cm grid in the
asset frame with two vertical rays per sample (computed exactly by rasterising the mesh's
triangles onto the grid, no ray-tracing library needed): straight down from 5 cm above the surface (the first
hit must be within :data:`SUPPORT_TOL` of ``h``: the point is *supported*) and straight up from
just above it (the distance to the next part of the mesh is the *free height* there; 0 when the
ray crosses the mesh an odd number of times, i.e. the point is inside the model's material). A
candidate footprint is accepted when its centre and at least :data:`MIN_SUPPORTED` of a grid of
points over it (spaced at most one map step, at least 5 x 5) are supported, and the free height
at every such point (the smallest over the cell's 3 x 3 neighbourhood, so thin legs or rails
between samples count) exceeds the object's height. Maps are cached per (catalog, asset, surface).
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from ...contracts import MeshData, SupportSurface

SUPPORT_TOL = 0.005  # the mesh top may differ from the surface height by this much, m
MIN_SUPPORTED = 0.6  # fraction of footprint samples that must be supported
STEP = 0.02  # map resolution, m
LIFT = 0.05  # the downward rays start this far above the surface, m
SAMPLES = 5  # footprint samples per side

_CACHE: OrderedDict[tuple, "SurfaceMap"] = OrderedDict()
_CACHE_SIZE = 256
_LOCK = threading.Lock()


@dataclass(frozen=True)
class SurfaceMap:
    """Samples of one surface: cell (j, i) is centred at (x0 + i step, y0 + j step), asset frame.

    supported (ny, nx) bool; free (ny, nx) float64 metres (inf when nothing is above).
    """

    x0: float
    y0: float
    step: float
    supported: np.ndarray
    free: np.ndarray

    def footprint_ok(self, lx: np.ndarray, ly: np.ndarray, lyaw: np.ndarray, width: float, depth: float,
                     height: float) -> np.ndarray:
        """(n,) bool: candidate footprints (centre and yaw in the asset frame) rest on the mesh."""
        n = len(lx)
        if n == 0:
            return np.zeros(0, dtype=bool)
        nu = int(np.clip(np.ceil(width / self.step) + 1, SAMPLES, 9))
        nv = int(np.clip(np.ceil(depth / self.step) + 1, SAMPLES, 9))
        u, v = np.meshgrid(np.linspace(-0.49, 0.49, nu) * width, np.linspace(-0.49, 0.49, nv) * depth)
        u, v = u.ravel(), v.ravel()
        c, s = np.cos(lyaw)[:, None], np.sin(lyaw)[:, None]
        px = lx[:, None] + c * u[None] - s * v[None]
        py = ly[:, None] + s * u[None] + c * v[None]
        ny, nx = self.supported.shape
        i = np.rint((px - self.x0) / self.step).astype(np.int64)
        j = np.rint((py - self.y0) / self.step).astype(np.int64)
        on = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
        i, j = np.clip(i, 0, nx - 1), np.clip(j, 0, ny - 1)
        sup = on & self.supported[j, i]
        free_ok = ~on | (self.free[j, i] > height + 0.002)
        centre = (nv // 2) * nu + nu // 2  # middle row and column (odd counts) or next to it
        return sup[:, centre] & (sup.mean(1) >= MIN_SUPPORTED) & free_ok.all(1)


def _vertical_hits(tri: np.ndarray, gx: np.ndarray, gy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where vertical lines through the grid points (gx (nx,), gy (ny,)) cross triangles (t, 3, 3).

    Returns (cell (k,) flat index into the (ny, nx) grid, z (k,)): one row per crossing. Each
    triangle is tested against the grid points inside its plan-view bounding box (barycentric
    test), so the work is proportional to the area the triangles cover.
    """
    nx, ny = len(gx), len(gy)
    x0, step = gx[0], gx[1] - gx[0] if nx > 1 else 1.0
    y0, stepy = gy[0], gy[1] - gy[0] if ny > 1 else 1.0
    lo = tri[:, :, :2].min(1)
    hi = tri[:, :, :2].max(1)
    i0 = np.clip(np.ceil((lo[:, 0] - x0) / step), 0, nx).astype(np.int64)
    i1 = np.clip(np.floor((hi[:, 0] - x0) / step) + 1, 0, nx).astype(np.int64)
    j0 = np.clip(np.ceil((lo[:, 1] - y0) / stepy), 0, ny).astype(np.int64)
    j1 = np.clip(np.floor((hi[:, 1] - y0) / stepy) + 1, 0, ny).astype(np.int64)
    wi, wj = np.maximum(i1 - i0, 0), np.maximum(j1 - j0, 0)
    count = wi * wj
    keep = np.flatnonzero(count > 0)
    if len(keep) == 0:
        return np.zeros(0, np.int64), np.zeros(0)
    tid = np.repeat(keep, count[keep])
    start = np.repeat(np.cumsum(count[keep]) - count[keep], count[keep])
    local = np.arange(len(tid)) - start
    ii = i0[tid] + local % wi[tid]
    jj = j0[tid] + local // wi[tid]
    px, py = gx[ii], gy[jj]
    a, b, c = tri[tid, 0], tri[tid, 1], tri[tid, 2]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    ok = np.abs(det) > 1e-14
    det = np.where(ok, det, 1.0)
    l1 = ((px - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (py - a[:, 1])) / det
    l2 = ((b[:, 0] - a[:, 0]) * (py - a[:, 1]) - (px - a[:, 0]) * (b[:, 1] - a[:, 1])) / det
    inside = ok & (l1 >= 0) & (l2 >= 0) & (l1 + l2 <= 1)
    z = a[:, 2] + l1 * (b[:, 2] - a[:, 2]) + l2 * (c[:, 2] - a[:, 2])
    return (jj * nx + ii)[inside], z[inside]


def surface_map(key: tuple, mesh: MeshData, surf: SupportSurface, bounds: tuple[float, float, float, float]) -> SurfaceMap:
    """The (cached) map of ``surf`` on ``mesh`` (asset frame) over ``bounds`` (minx, miny, maxx, maxy)."""
    with _LOCK:
        hit = _CACHE.get(key)
        if hit is not None:
            _CACHE.move_to_end(key)
            return hit
    minx, miny, maxx, maxy = bounds
    # A tiny offset keeps grid points off the mesh's edges (the polygon came from those edges),
    # so no crossing is counted twice.
    gx = np.arange(minx, maxx + STEP / 2, STEP) + STEP * 0.0137
    gy = np.arange(miny, maxy + STEP / 2, STEP) + STEP * 0.0071
    shape = (len(gy), len(gx))
    n = shape[0] * shape[1]
    h = float(surf.height)
    tri = mesh.vertices.astype(np.float64)[mesh.faces]
    tlo, thi = tri.min(1), tri.max(1)
    near = ((thi[:, 0] >= gx[0]) & (tlo[:, 0] <= gx[-1]) & (thi[:, 1] >= gy[0]) & (tlo[:, 1] <= gy[-1])
            & (thi[:, 2] >= h - LIFT))
    cell, z = _vertical_hits(tri[near], gx, gy)
    # Down from h + LIFT: the highest crossing below that height.
    z_top = np.full(n, -np.inf)
    below = z <= h + LIFT
    np.maximum.at(z_top, cell[below], z[below])
    supported = np.abs(z_top - h) <= SUPPORT_TOL
    # Up from just above the top found (or h): the nearest crossing above, and their parity.
    start = np.where(supported, z_top, h) + 0.001
    above = z > start[cell]
    free = np.full(n, np.inf)
    np.minimum.at(free, cell[above], z[above] - h)
    # An odd number of crossings above means the point is inside the mesh's material (a
    # "surface" found between two parts of a closed model): nothing can stand there.
    free[np.bincount(cell[above], minlength=n) % 2 == 1] = 0.0
    # Thin parts (legs, ropes, rails) can slip between samples: each cell keeps the smallest free
    # height of its 3 x 3 neighbourhood.
    free_min = ndimage.minimum_filter(free.reshape(shape), size=3, mode="nearest")
    result = SurfaceMap(float(gx[0]), float(gy[0]), STEP, supported.reshape(shape), free_min)
    with _LOCK:
        _CACHE[key] = result
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    return result
