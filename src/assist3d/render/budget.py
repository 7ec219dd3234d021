"""A ray budget for one view: cast a coarse lattice of pixels, refine only where it is needed.

``render.rays = "adaptive"``. The image is covered by square tiles whose corners are pixels on a
lattice of stride ``render.ray_tile``. A tile whose four corner rays hit the *same triangle* is
*flat*: a triangle is convex and the rays through a tile's pixels span the convex hull of its
corner rays, so every pixel of the tile hits that triangle's plane inside that triangle. Its
depths are then computed exactly by ray-plane intersection, with no ray cast. Every other tile
(corners on different triangles, an edge, a miss) is split in four and its new corner pixels are
cast, down to single pixels, which are all cast.

The result is a full-resolution (t, face) pair for the view, equal to the full render's up to the
rounding of the depth (float32) wherever nothing smaller than a tile stands in front of a flat
tile's triangle without touching one of its corner rays. Everything downstream (depth sensor,
per-voxel picks, colours, labels) is unchanged, so the same pixels pick the same points.

Rays that leave the scene (a room has no ceiling by default) would all be cast, since a miss has no
triangle to be flat on. So a ray that misses the scene is cast once more, against a *sky box*
alone (:func:`sky_box`, an axis-aligned box a metre outside the scene's bounds, 12 triangles), and
a tile whose corners hit one sky triangle is flat like any other (nothing smaller than a tile may
stand in front of it, as above). Sky hits are reported as misses (t = inf, face = -1). The scene's
own rays go through the caster of the full render, so where two triangles coincide, both pick the
same one.

``render.rays = "footprint"`` (``cast_adaptive(..., spacing=...)``) samples the view instead of
reproducing it: from a tile's corner rays, the exact distance between the surface points of
neighbouring pixels (the derivative of the hit point on the hit triangle's plane, :func:`_footprint`)
says how coarse a lattice still samples what the tile sees at most ``spacing`` apart. A flat tile
keeps only that sub-lattice (from its plane), a tile whose corners hit different triangles of the
scene closes as soon as its corners are that close, and the pixels between are left out (misses).
How much of the full render's data it keeps, and for how many rays: docs/generation.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.contracts import Camera, SceneMesh
from .raycast import RayCaster

__all__ = ["FacePlanes", "face_planes", "sky_box", "lattice", "cast_adaptive"]

#: the 12 edges of a box whose 8 corners are numbered 4 i + 2 j + k (i, j, k: max in x, y, z)
_EDGES = np.array([(c, c | bit) for bit in (1, 2, 4) for c in range(8) if not c & bit])


@dataclass(frozen=True)
class FacePlanes:
    """What the budget needs of a scene: the plane of every triangle, ``normal`` (F, 3) float64
    (by winding, unnormalised) and ``offset`` (F,) float64 with ``normal . x = offset`` on it; and
    ``bars`` (B, 8, 3) float64, the corners of an oriented box around every *slender* part of an
    object (see :func:`slender_parts`): the parts a coarse lattice of rays can step over; and
    ``bar_of_face`` (F,) int64, the slender part each triangle belongs to (-1 for none);
    ``scene_faces``: where the planes of a sky box (:func:`sky_box`) follow the scene's, the number of
    the scene's triangles (a hit on a triangle from there on is a miss); None when there is none."""

    normal: np.ndarray
    offset: np.ndarray
    bars: np.ndarray
    bar_of_face: np.ndarray | None = None
    scene_faces: int | None = None


#: a connected part of an object whose middle extent is below this (m) is slender: a rod, a slat,
#: a leg, a handle, a small thing (a chair's leg is ~4 cm, a crib's bar or a blind's slat 2-5 cm)
SLENDER = 0.08


def slender_parts(scene: SceneMesh, limit: float = SLENDER) -> np.ndarray:
    """(B, 8, 3) float64 corners of the oriented (principal-axis) boxes of the connected parts of
    the objects (faces with an instance id) whose second-largest extent is below ``limit`` metres."""
    return _slender(scene, limit)[0]


def _slender(scene: SceneMesh, limit: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`slender_parts` and (F,) int64 the index of the slender part of each triangle (-1)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    of_face = np.full(len(scene.faces), -1, np.int64)
    obj = np.flatnonzero(scene.face_instance >= 0)
    if len(obj) == 0:
        return np.zeros((0, 8, 3)), of_face
    f = scene.faces[obj]
    used, inv = np.unique(f, return_inverse=True)
    f = inv.reshape(f.shape)
    nv = len(used)
    edges = coo_matrix((np.ones(2 * len(f)), (np.r_[f[:, 0], f[:, 1]], np.r_[f[:, 1], f[:, 2]])), shape=(nv, nv))
    n, part = connected_components(edges, directed=False)
    v = scene.vertices[used].astype(np.float64)
    count = np.bincount(part, minlength=n).astype(np.float64)
    mean = np.stack([np.bincount(part, v[:, j], minlength=n) for j in range(3)], axis=1) / count[:, None]
    d = v - mean[part]
    cov = np.zeros((n, 3, 3))
    for i in range(3):
        for j in range(i, 3):
            cov[:, i, j] = cov[:, j, i] = np.bincount(part, d[:, i] * d[:, j], minlength=n)
    _, axes = np.linalg.eigh(cov)  # (n, 3, 3): columns are the principal axes
    local = np.einsum("vj,vjk->vk", d, axes[part])
    lo = np.full((n, 3), np.inf)
    hi = np.full((n, 3), -np.inf)
    np.minimum.at(lo, part, local)
    np.maximum.at(hi, part, local)
    thin = np.sort(hi - lo, axis=1)[:, 1] < limit
    number = np.full(n, -1, np.int64)
    number[thin] = np.arange(int(thin.sum()))
    of_face[obj] = number[part[f[:, 0]]]
    pick = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    box = np.stack([lo[thin], hi[thin]], axis=1)  # (B, 2, 3) in the parts' own axes
    corners_local = np.stack([box[:, pick[:, a], a] for a in range(3)], axis=-1)  # (B, 8, 3)
    return mean[thin][:, None, :] + np.einsum("bck,bjk->bcj", corners_local, axes[thin]), of_face


def sky_box(scene: SceneMesh, margin: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (8, 3) float32 and triangles (12, 3) int32 of an axis-aligned box ``margin`` metres
    outside the bounds of ``scene``: every ray from inside the bounds hits it."""
    lo = scene.vertices.min(0).astype(np.float64) - margin
    hi = scene.vertices.max(0).astype(np.float64) + margin
    corners = np.array([[(hi if i else lo)[0], (hi if j else lo)[1], (hi if k else lo)[2]]
                        for i in (0, 1) for j in (0, 1) for k in (0, 1)], np.float32)  # 4 i + 2 j + k
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return corners, np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], np.int32)


def _planes(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    tri = vertices[faces].astype(np.float64)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    return n, np.einsum("ij,ij->i", n, tri[:, 0])


def face_planes(scene: SceneMesh, *, sky: bool = False) -> FacePlanes:
    """Planes of all triangles of ``scene`` (float64, from its float32 vertices) and its slender parts;
    with ``sky``, followed by the planes of its :func:`sky_box` (triangle ``F + j`` is the box's ``j``)."""
    n, off = _planes(scene.vertices, scene.faces)
    bars, of_face = _slender(scene, SLENDER)
    if not sky:
        return FacePlanes(n, off, bars, of_face)
    n_sky, off_sky = _planes(*sky_box(scene))
    return FacePlanes(np.concatenate([n, n_sky]), np.concatenate([off, off_sky]), bars,
                      np.append(of_face, np.full(len(n_sky), -1, np.int64)), len(scene.faces))


def _bar_images(planes: FacePlanes, camera: Camera) -> tuple[np.ndarray, ...]:
    """The image of every slender part's box in front of the camera: ``(bar, v0, v1, u0, u1, z)``,
    (k,) each: its index, the pixel rectangle around its projection widened by a pixel, and its
    nearest camera depth. Conservative: a box is clipped at the camera plane first."""
    empty = np.zeros(0)
    if len(planes.bars) == 0:
        return np.zeros(0, np.int64), empty, empty, empty, empty, empty
    rot, c = camera.pose[:3, :3], camera.pose[:3, 3]
    pc = (planes.bars - c) @ rot  # (B, 8, 3) camera frame
    eps = 1e-3
    # clip each box at the plane z = eps: its image is that of its corners in front and of the
    # points where its edges cross the plane
    a, b = _EDGES[:, 0], _EDGES[:, 1]
    za, zb = pc[:, a, 2], pc[:, b, 2]
    cross = (za - eps) * (zb - eps) < 0
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(cross, (eps - za) / (zb - za), 0.0)
    xing = pc[:, a] + w[..., None] * (pc[:, b] - pc[:, a])
    pts = np.concatenate([pc, xing], axis=1)  # (B, 20, 3)
    keep = np.concatenate([pc[..., 2] >= eps, cross], axis=1)
    bar = np.flatnonzero(keep.any(axis=1))
    pts, keep = pts[bar], keep[bar]
    z = np.where(keep, np.maximum(pts[..., 2], eps), 1.0)
    u = camera.fx * pts[..., 0] / z + camera.cx
    v = camera.fy * pts[..., 1] / z + camera.cy
    inf = np.inf
    u0 = np.floor(np.where(keep, u, inf).min(axis=1)) - 1
    u1 = np.ceil(np.where(keep, u, -inf).max(axis=1)) + 1
    v0 = np.floor(np.where(keep, v, inf).min(axis=1)) - 1
    v1 = np.ceil(np.where(keep, v, -inf).max(axis=1)) + 1
    zmin = np.where(keep, z, inf).min(axis=1)
    on = (u1 >= 0) & (u0 <= camera.width - 1) & (v1 >= 0) & (v0 <= camera.height - 1)
    return bar[on], v0[on], v1[on], u0[on], u1[on], zmin[on]


#: at most this many (part, cell) pairs are expanded at once in :func:`_occluders` (bounds its memory)
_OCCLUDER_CHUNK = 1 << 16


def _occluders(images: tuple[np.ndarray, ...], rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per cell of the lattice ``rows`` x ``cols``, over the slender parts' images (from
    :func:`_bar_images`) that overlap it: the nearest depth ``z1`` (r, c) float64 (inf = none),
    the part at that depth ``id1`` (r, c) int64 (-2 = none), and the nearest depth of any other
    part ``z2``."""
    nr, nc = len(rows) - 1, len(cols) - 1
    z1 = np.full(nr * nc, np.inf)
    z2 = np.full(nr * nc, np.inf)
    id1 = np.full(nr * nc, -2, np.int64)
    bar, v0, v1, u0, u1, zmin = images
    if len(bar):
        # cells [rows[i], rows[i+1]] overlapping [v0, v1]: i in [i0, i1)
        i0 = np.clip(np.searchsorted(rows, v0, side="right") - 1, 0, nr)
        i1 = np.clip(np.searchsorted(rows, v1, side="left"), 0, nr)
        j0 = np.clip(np.searchsorted(cols, u0, side="right") - 1, 0, nc)
        j1 = np.clip(np.searchsorted(cols, u1, side="left"), 0, nc)
        hi_i, hi_j = np.maximum(i1 - i0, 0), np.maximum(j1 - j0, 0)
        size = hi_i * hi_j
        # the parts in runs, in their order, a run those whose first cell falls in one block of
        # _OCCLUDER_CHUNK cells (so a run holds at most that many and one part more)
        block = (np.cumsum(size) - size) // _OCCLUDER_CHUNK
        cuts = [0, *(np.flatnonzero(np.diff(block)) + 1).tolist(), len(size)]

        def expand(a: int, b: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            sz = size[a:b]
            k = a + np.repeat(np.arange(b - a), sz)
            m = np.arange(len(k)) - np.repeat(np.cumsum(sz) - sz, sz)
            return (i0[k] + m // hi_j[k]) * nc + j0[k] + m % hi_j[k], zmin[k], bar[k]

        runs = [(a, b) for a, b in zip(cuts[:-1], cuts[1:]) if size[a:b].sum()]
        one = expand(*runs[0]) if len(runs) == 1 else None
        for a, b in runs:  # nearest depth per cell
            cell, z, _ = one or expand(a, b)
            np.minimum.at(z1, cell, z)
        for a, b in runs:  # the part at that depth (the last of equals)
            cell, z, who = one or expand(a, b)
            first = z == z1[cell]
            id1[cell[first]] = who[first]
        for a, b in runs:  # the nearest depth of any other part
            cell, z, who = one or expand(a, b)
            other = who != id1[cell]
            np.minimum.at(z2, cell[other], z[other])
    return z1.reshape(nr, nc), id1.reshape(nr, nc), z2.reshape(nr, nc)


def lattice(n: int, stride: int) -> np.ndarray:
    """(k,) int64 lattice coordinates along an axis of ``n`` pixels: multiples of ``stride`` and
    the last pixel. The lattice of ``stride / 2`` contains the lattice of ``stride``."""
    pts = np.arange(0, n, stride, dtype=np.int64)
    return pts if pts[-1] == n - 1 else np.append(pts, n - 1)


def _footprint(planes: FacePlanes, camera: Camera, rot: np.ndarray, lat_face: np.ndarray, lat_t: np.ndarray,
               u: np.ndarray, v: np.ndarray, where: np.ndarray) -> np.ndarray:
    """(r, c) float64 metres between the surface points of neighbouring pixels at lattice points.

    At the pixel (u, v) (camera-frame direction d = (u, v, 1), ``u``/``v`` the normalised
    coordinates of the lattice's columns and rows) whose ray hit triangle ``lat_face`` at depth
    ``lat_t``, the hit point moves by ``dP/du = t / fx (e_x - d a_x / (a . d))`` for a step of one pixel
    (``a``: the triangle's normal in the camera frame), likewise in v; the larger of the two lengths.
    inf where the ray missed the scene (a miss, the sky box) or grazes its plane, and off ``where``."""
    out = np.full(lat_face.shape, np.inf)
    scene_hit = where & (lat_face >= 0)
    if planes.scene_faces is not None:
        scene_hit &= lat_face < planes.scene_faces
    ri, ci = np.nonzero(scene_hit)
    if len(ri) == 0:
        return out
    a = planes.normal[lat_face[ri, ci]] @ rot  # (k, 3) camera-frame normals
    du, dv = u[ci], v[ri]
    d2 = du * du + dv * dv + 1.0
    ad = a[:, 0] * du + a[:, 1] * dv + a[:, 2]
    t = lat_t[ri, ci].astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.zeros(len(ri))
        for comp, dc, focal in ((0, du, camera.fx), (1, dv, camera.fy)):
            q = a[:, comp] / ad  # |e - d q|^2 = 1 - 2 d_c q + q^2 |d|^2
            g = np.maximum(g, t / focal * np.sqrt(np.maximum(1.0 - 2.0 * dc * q + q * q * d2, 0.0)))
    out[ri, ci] = np.where(np.isfinite(g), g, np.inf)
    return out


def cast_adaptive(caster: RayCaster, planes: FacePlanes, camera: Camera, dirs: np.ndarray,
                  tile: int, sky: RayCaster | None = None,
                  spacing: float | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """(t (H*W,) float32, face (H*W,) int32, rays cast) of one view, as ``caster.cast`` over all its
    pixels would give (see the module docs for where it can differ).

    dirs (H*W, 3) float32 world directions of the camera's pixels, row-major; tile a power of two
    >= 1 (1 casts every pixel). ``sky``: a caster over the :func:`sky_box` alone, used where
    ``planes`` hold its planes (``face_planes(scene, sky=True)``).

    ``spacing`` (metres; ``render.rays = "footprint"``): the view is *sampled* instead: wherever the
    surfaces a tile sees are already sampled at most ``spacing`` apart by a coarser lattice of pixels,
    only that lattice is kept (computed on a flat tile; on a tile whose four corners hit different
    triangles of the scene, its cast corners); the tile's other pixels are left out, as misses (t inf,
    face -1). Elsewhere (edges against the sky, grazing planes) tiles refine to single pixels as above.
    """
    width, height = camera.width, camera.height
    center = camera.pose[:3, 3].astype(np.float32)
    n = width * height
    t = np.full(n, np.inf, np.float32)
    face = np.full(n, -1, np.int32)
    done = np.zeros(n, bool)
    # footprint: what is left to cast pixel by pixel at the end (the pixels of the tiles still open at
    # the last level and those a grazing plane left), instead of every pixel not known yet
    left = np.zeros(n, bool) if spacing is not None else None
    cast = 0

    def run(idx: np.ndarray) -> None:
        nonlocal cast
        idx = idx[~done[idx]]
        if len(idx) == 0:
            return
        origins = np.empty((len(idx), 3), np.float32)
        origins[:] = center
        d = dirs[idx]
        tt, ff = caster.cast(origins, d)
        if sky is not None and planes.scene_faces is not None:  # a miss: which sky triangle
            out = np.flatnonzero(ff < 0)
            if len(out):
                tt[out], f_sky = sky.cast(origins[out], d[out])
                ff[out] = np.where(f_sky >= 0, f_sky + planes.scene_faces, -1)
        t[idx], face[idx] = tt, ff
        done[idx] = True
        cast += len(idx)

    face_img = face.reshape(height, width)
    t_img = t.reshape(height, width)
    s = max(1, int(tile))
    rows, cols = lattice(height, s), lattice(width, s)
    if len(rows) < 2 or len(cols) < 2 or s == 1:
        run(np.arange(n))
        return t, face, cast
    images = _bar_images(planes, camera)
    bar_of_face = planes.bar_of_face if planes.bar_of_face is not None else np.full(len(planes.offset), -1)
    active = np.ones((len(rows) - 1, len(cols) - 1), bool)
    offset = planes.offset - planes.normal @ center.astype(np.float64)  # per plane: n . (v0 - c)
    # a plane's n . d over the pixels is separable: (R^T n) . ((u - cx) / fx, (v - cy) / fy, 1)
    rot = camera.pose[:3, :3].astype(np.float64)
    u_of = (np.arange(width, dtype=np.float64) - camera.cx) / camera.fx
    v_of = (np.arange(height, dtype=np.float64) - camera.cy) / camera.fy
    def block(ti: np.ndarray, tj: np.ndarray, off: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows (k, m), columns (k, m) and pixels (k, m * m) of the tiles (ti, tj) at offsets ``off``
        from their first corner (a tile's last row and column are its neighbours' first; offsets past
        a short last tile are clipped onto its edge, where they repeat a pixel)."""
        r = np.minimum(rows[ti][:, None] + off, rows[ti + 1][:, None])
        c = np.minimum(cols[tj][:, None] + off, cols[tj + 1][:, None])
        return r, c, (r[:, :, None] * width + c[:, None, :]).reshape(len(ti), len(off) ** 2)

    def fill(ti: np.ndarray, tj: np.ndarray, off: np.ndarray, ft: np.ndarray) -> None:
        """Depth and triangle of the pixels at ``off`` of the flat tiles (ti, tj) on triangles ``ft``."""
        r, c, blk = block(ti, tj, off)
        # per pixel n . d from the tile plane's camera-frame normal, in float64 (the depth is then
        # that of the exact pixel ray; the caster's float32 ray may round it the other way)
        a = planes.normal[ft] @ rot  # (k, 3)
        den = (a[:, 0, None] * u_of[c])[:, None, :] + (a[:, 1, None] * v_of[r] + a[:, 2, None])[:, :, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            depth = (offset[ft][:, None] / den.reshape(len(ti), -1)).astype(np.float32)
        # a grazing plane is left to be cast; a pixel already known keeps its value
        good = ~done[blk] & np.isfinite(depth) & (depth > 0)
        idx = blk[good]
        t[idx] = depth[good]
        face[idx] = np.broadcast_to(ft[:, None], blk.shape)[good]
        done[idx] = True
        if left is not None:
            left[blk[~good]] = True  # (those known already are not cast again)

    def sample_level(lat: np.ndarray, ti: np.ndarray, tj: np.ndarray, flat: np.ndarray,
                     corner: np.ndarray) -> tuple[list, np.ndarray]:
        """``spacing``: the flat tiles (ti, tj) grouped by the stride of the lattice that samples their
        surface ``spacing`` apart, [(ti, tj, offsets), ...], and the tiles this level closes: the flat
        ones and the others whose corners already sample what they see finely enough."""
        assert spacing is not None
        tl = t_img[np.ix_(rows, cols)]
        g_lat = _footprint(planes, camera, rot, lat, tl, u_of[cols], v_of[rows], corner)
        # per tile the largest step over its corners (inf: a corner off the scene or on a grazing plane)
        g = np.maximum(np.maximum(g_lat[:-1, :-1], g_lat[1:, :-1]), np.maximum(g_lat[:-1, 1:], g_lat[1:, 1:]))
        with np.errstate(divide="ignore"):
            k = np.exp2(np.floor(np.log2(spacing / g[ti, tj]))) if len(ti) else np.zeros(0)
        k = np.clip(np.nan_to_num(k, nan=1.0), 1, s).astype(np.int64)
        ft = lat[:-1, :-1][ti, tj]
        if planes.scene_faces is not None:  # a flat tile on the sky holds only misses
            k[ft >= planes.scene_faces] = s
        # a tile whose corners hit different triangles of the scene closes when they sample every surface
        # they hit at most ``spacing`` apart. No slender-part guard: whatever stands in front of such a tile
        # without touching a corner is narrower than the tile, so thinner than ``spacing`` (it is nearer
        # than the corners' surfaces, where the tile spans at most that)
        near = active & ~flat & (s * g <= spacing)
        closed = flat | near
        groups = []
        for step in np.unique(k[k < s]):  # at step s the corners, cast already, are the lattice
            m = k == step
            groups.append((ti[m], tj[m], np.arange(0, s + 1, int(step))))
        return groups, closed

    while s > 1:
        # cast the corners of the tiles still open at this level
        corner = np.zeros((len(rows), len(cols)), bool)
        corner[:-1, :-1] |= active
        corner[1:, :-1] |= active
        corner[:-1, 1:] |= active
        corner[1:, 1:] |= active
        rr, cc = np.nonzero(corner)
        run(rows[rr] * width + cols[cc])
        lat = face_img[np.ix_(rows, cols)]
        f00 = lat[:-1, :-1]
        flat = active & (f00 >= 0) & (f00 == lat[1:, :-1]) & (f00 == lat[:-1, 1:]) & (f00 == lat[1:, 1:])
        ti, tj = np.nonzero(flat)
        if len(ti):  # ... and no slender part may stand in front of the tile
            tl = t_img[np.ix_(rows, cols)]
            deepest = np.maximum(np.maximum(tl[ti, tj], tl[ti + 1, tj]), np.maximum(tl[ti, tj + 1], tl[ti + 1, tj + 1]))
            z1, id1, z2 = _occluders(images, rows, cols)
            own = bar_of_face[f00[ti, tj]]  # a slender part cannot stand in front of itself
            z1, id1, z2 = z1[ti, tj], id1[ti, tj], z2[ti, tj]
            ok = np.where(id1 == own, z2, z1) >= deepest
            flat[ti[~ok], tj[~ok]] = False
            ti, tj = ti[ok], tj[ok]
        closed = flat  # the tiles this level finishes (the others are split)
        groups = [(ti, tj, np.arange(s + 1))]
        if spacing is not None:
            groups, closed = sample_level(lat, ti, tj, flat, corner)
        for gi, gj, off in groups:
            if len(gi):
                fill(gi, gj, off, lat[:-1, :-1][gi, gj])
        if s == 2 and left is not None:  # the tiles still open are cast pixel by pixel
            oi, oj = np.nonzero(active & ~closed)
            left[block(oi, oj, np.arange(3))[2]] = True
        s //= 2
        if s == 1:
            break
        rows2, cols2 = lattice(height, s), lattice(width, s)
        pr = np.searchsorted(rows, rows2[:-1], side="right") - 1
        pc = np.searchsorted(cols, cols2[:-1], side="right") - 1
        active = (active & ~closed).take(pr, axis=0).take(pc, axis=1)
        rows, cols = rows2, cols2
    # single pixels: every pixel not known yet (those of the tiles still open, and any a grazing
    # plane left) is cast; with ``spacing`` only those, not the pixels a coarser sampling left out
    run(np.flatnonzero(~done if left is None else left & ~done))
    if planes.scene_faces is not None:  # the sky is a miss
        sky = face >= planes.scene_faces
        face[sky] = -1
        t[sky] = np.inf
    return t, face, cast
