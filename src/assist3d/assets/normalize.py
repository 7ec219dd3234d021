"""Mesh normalisation shared by the importers.

Turns a loaded mesh (a trimesh ``Trimesh`` or ``Scene``) into :class:`~assist3d.core.contracts.MeshData`
in the canonical asset frame (z up, base at z = 0, footprint centred on x = y = 0, width along x,
depth along y, front facing -y), with one colour per face, and finds the horizontal surfaces other
objects can rest on (:func:`extract_supports`).

Everything here is vectorised over vertices and faces; the only Python loops run over the parts
(geometries / materials) of a mesh or over the few support surfaces found.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..core.contracts import MeshData, SupportSurface

log = logging.getLogger(__name__)

NEUTRAL_GREY = np.array([160, 160, 160], dtype=np.uint8)
AXES: dict[str, np.ndarray] = {
    "+x": np.array([1.0, 0.0, 0.0]), "-x": np.array([-1.0, 0.0, 0.0]),
    "+y": np.array([0.0, 1.0, 0.0]), "-y": np.array([0.0, -1.0, 0.0]),
    "+z": np.array([0.0, 0.0, 1.0]), "-z": np.array([0.0, 0.0, -1.0]),
}
CLEARANCE_COVER = 0.5  # faces above must cover this fraction of a surface (x-y area) to bound it
TEXTURE_MAX_PX = 128  # textures are shrunk to this size before sampling (colours are averaged anyway)


class MeshRejected(ValueError):
    """A mesh that cannot be used; the message is a one-line reason."""


# --------------------------------------------------------------------------------------------
# Frames
# --------------------------------------------------------------------------------------------


def parse_axis(axis: str) -> np.ndarray:
    """``'+y'``, ``'y'``, ``'-z'``... -> a unit vector (3,) float64; a clear error otherwise."""
    a = axis.strip().lower()
    if a in ("x", "y", "z"):
        a = "+" + a
    if a not in AXES:
        raise ValueError(f"axis {axis!r}: expected one of x, y, z, +x, -x, +y, -y, +z, -z")
    return AXES[a]


def axes_rotation(up: str = "+z", front: str = "-y") -> np.ndarray:
    """(3, 3) float64 rotation taking the source ``up`` axis to +z and ``front`` axis to -y.

    Sweet Home 3D / glTF / most OBJ files: ``up='+y', front='+z'``. ShapeNet: ``up='+y',
    front='-z'``... A right-handed rotation (det +1): the mesh is never mirrored.
    """
    u, f = parse_axis(up), parse_axis(front)
    if abs(float(u @ f)) > 0.5:
        raise ValueError(f"up axis {up!r} and front axis {front!r} must be perpendicular")
    # rows: where each canonical axis comes from; canonical x = y_canonical x z_canonical
    back = -f  # canonical +y
    x = np.cross(back, u)
    return np.stack([x, back, u])


def to_canonical(vertices: np.ndarray, *, rotation: np.ndarray | None = None,
                 size: Sequence[float] | None = None, scale: float | None = None) -> np.ndarray:
    """Rotate, scale and place vertices in the canonical frame.

    vertices: (V, 3) float; rotation: (3, 3) applied as ``v @ rotation.T``; ``size`` (w, d, h)
    metres scales each axis so the bounding box is exactly that size (what Sweet Home 3D does);
    otherwise ``scale`` multiplies uniformly (default 1). The footprint is centred at x = y = 0 and
    the base put at z = 0. Returns (V, 3) float64.
    """
    v = np.asarray(vertices, dtype=np.float64)
    if rotation is not None:
        v = v @ np.asarray(rotation, dtype=np.float64).T
    lo, hi = v.min(0), v.max(0)
    ext = hi - lo
    if size is not None:
        target = np.asarray(size, dtype=np.float64)
        if target.shape != (3,) or not np.all(np.isfinite(target)) or np.any(target <= 0):
            raise MeshRejected(f"target size {tuple(size)} must be three positive numbers (w, d, h) in metres")
        factor = target / np.where(ext > 0, ext, 1.0)
    else:
        factor = np.full(3, 1.0 if scale is None else float(scale))
    centre = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    return (v - centre) * factor


# --------------------------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------------------------


def validate_mesh(vertices: np.ndarray, faces: np.ndarray, *, min_extent: float = 1e-9) -> str | None:
    """A one-line reason why the mesh is unusable, or ``None`` if it is fine.

    Rejects: no faces, faces indexing missing vertices, NaN/inf coordinates, and a bounding box
    with zero extent along any axis (a point, a line or a flat sheet).
    """
    v = np.asarray(vertices)
    f = np.asarray(faces)
    if v.ndim != 2 or v.shape[-1] != 3 or len(v) == 0:
        return "empty mesh: no vertices"
    if f.ndim != 2 or f.shape[-1] != 3 or len(f) == 0:
        return "empty mesh: no triangles"
    if f.min() < 0 or f.max() >= len(v):
        return f"corrupt mesh: face index out of range (0..{len(v) - 1})"
    mask = np.zeros(len(v), dtype=bool)
    mask[f.ravel()] = True
    used = v[mask]
    if not np.all(np.isfinite(used)):
        bad = int((~np.isfinite(used).all(1)).sum())
        return f"invalid mesh: {bad} vertices are NaN or infinite"
    ext = used.max(0) - used.min(0)
    if np.any(ext <= min_extent * max(1.0, float(ext.max()))):
        return f"degenerate mesh: zero extent along {'xyz'[int(np.argmin(ext))]} (bounding box {np.round(ext, 6).tolist()})"
    return None


# --------------------------------------------------------------------------------------------
# Colours
# --------------------------------------------------------------------------------------------


def _rgb(c: Any) -> np.ndarray | None:
    """(3,) float64 colour in 0..255 from an RGB(A) value given as uint8 or as floats in 0..1."""
    if c is None:
        return None
    a = np.asarray(c)
    if a.size < 3:
        return None
    rgb = a.ravel()[:3].astype(np.float64)
    if not np.all(np.isfinite(rgb)):
        return None
    if a.dtype.kind == "f" and rgb.max() <= 1.0:
        rgb = rgb * 255.0
    return np.clip(rgb, 0, 255)


def image_array(image: Any) -> np.ndarray | None:
    """A small (h, w, 3) float64 copy of a PIL image, or None."""
    if image is None:
        return None
    try:
        img = image
        if hasattr(img, "draft") and getattr(img, "format", None) == "JPEG":
            img.draft("RGB", (TEXTURE_MAX_PX, TEXTURE_MAX_PX))
        img = img.convert("RGB")
        if max(img.size) > TEXTURE_MAX_PX:
            img = img.copy()
            img.thumbnail((TEXTURE_MAX_PX, TEXTURE_MAX_PX))
        arr = np.asarray(img, dtype=np.float64)
    except Exception as e:  # PIL raises many types for broken images
        log.debug("texture unreadable: %s", e)
        return None
    if arr.ndim != 3 or arr.shape[0] == 0 or arr.shape[1] == 0:
        return None
    return arr


def sample_texture(arr: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Colours (n, 3) float64 of the texture at UVs (n, 2), wrapping like a repeating texture."""
    h, w = arr.shape[:2]
    u = np.mod(uv[:, 0], 1.0)
    v = np.mod(uv[:, 1], 1.0)
    col = np.clip((u * w).astype(np.int64), 0, w - 1)
    row = np.clip(((1.0 - v) * h).astype(np.int64), 0, h - 1)
    return arr[row, col]


def _material_colour(material: Any) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(base colour (3,) 0..255 or None, texture array or None) of a trimesh material."""
    if material is None:
        return None, None
    base = None
    image = None
    if hasattr(material, "baseColorFactor") or hasattr(material, "baseColorTexture"):  # PBR (glTF)
        base = _rgb(getattr(material, "baseColorFactor", None))
        image = getattr(material, "baseColorTexture", None)
    else:  # SimpleMaterial (OBJ/MTL): diffuse is RGBA uint8
        base = _rgb(getattr(material, "diffuse", None))
        image = getattr(material, "image", None)
    return base, image_array(image)


def face_colors_of(geometry: Any) -> np.ndarray:
    """(F, 3) uint8 colour per face of one trimesh geometry.

    Order of preference: the texture sampled at each face's UV centroid (modulated by a non-white
    base colour), the material's diffuse / base colour, vertex or face colours, neutral grey.
    """
    n = len(geometry.faces)
    visual = getattr(geometry, "visual", None)
    kind = getattr(visual, "kind", None)
    out = np.tile(NEUTRAL_GREY.astype(np.float64), (n, 1))
    if visual is None or n == 0:
        return out.astype(np.uint8)
    if kind == "texture" or hasattr(visual, "material"):
        base, tex = _material_colour(getattr(visual, "material", None))
        uv = getattr(visual, "uv", None)
        if tex is not None and uv is not None and len(uv) == len(geometry.vertices):
            uv = np.asarray(uv, dtype=np.float64)
            if np.all(np.isfinite(uv)):
                centroid_uv = uv[np.asarray(geometry.faces)].mean(axis=1)
                out = sample_texture(tex, centroid_uv)
                if base is not None and base.min() < 250:
                    out = out * (base / 255.0)
                return np.clip(np.rint(out), 0, 255).astype(np.uint8)
        if tex is not None:
            out[:] = tex.reshape(-1, 3).mean(0)
            if base is not None and base.min() < 250:
                out = out * (base / 255.0)
            return np.clip(np.rint(out), 0, 255).astype(np.uint8)
        if base is not None:
            out[:] = base
            return np.clip(np.rint(out), 0, 255).astype(np.uint8)
        return out.astype(np.uint8)
    if kind == "face":
        fc = np.asarray(visual.face_colors)
        if fc.shape[0] == n:
            return np.clip(fc[:, :3], 0, 255).astype(np.uint8)
    if kind == "vertex":
        vc = np.asarray(visual.vertex_colors, dtype=np.float64)
        if vc.shape[0] == len(geometry.vertices):
            return np.clip(np.rint(vc[np.asarray(geometry.faces), :3].mean(axis=1)), 0, 255).astype(np.uint8)
    return out.astype(np.uint8)


# --------------------------------------------------------------------------------------------
# From trimesh to MeshData
# --------------------------------------------------------------------------------------------


def flatten_geometry(loaded: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices (V, 3) float64, faces (F, 3) int64, face colours (F, 3) uint8 of a Trimesh/Scene.

    A scene's node transforms are applied; point clouds and paths inside a scene are ignored.
    """
    import trimesh

    if isinstance(loaded, trimesh.Trimesh):
        parts = [(loaded, None)]
    elif isinstance(loaded, trimesh.Scene):
        parts = []
        for node in loaded.graph.nodes_geometry:
            transform, name = loaded.graph[node]
            geom = loaded.geometry.get(name)
            if isinstance(geom, trimesh.Trimesh):
                parts.append((geom, None if np.allclose(transform, np.eye(4)) else np.asarray(transform)))
    else:
        raise MeshRejected(f"not a triangle mesh ({type(loaded).__name__})")
    vs, fs, cs = [], [], []
    offset = 0
    for geom, transform in parts:
        v = np.asarray(geom.vertices, dtype=np.float64)
        f = np.asarray(geom.faces, dtype=np.int64)
        if len(f) == 0 or len(v) == 0:
            continue
        if transform is not None:
            v = v @ transform[:3, :3].T + transform[:3, 3]
        vs.append(v)
        fs.append(f + offset)
        cs.append(face_colors_of(geom))
        offset += len(v)
    if not fs:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), np.zeros((0, 3), dtype=np.uint8)
    return np.concatenate(vs), np.concatenate(fs), np.concatenate(cs)


def compact(vertices: np.ndarray, faces: np.ndarray, colors: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Drop unreferenced vertices and faces with a repeated vertex index (zero-area by index)."""
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    faces, colors = faces[keep], colors[keep]
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    remap = np.cumsum(used) - 1
    return vertices[used], remap[faces], colors


@dataclass(frozen=True)
class Normalized:
    """A normalised mesh and the facts an importer needs for the record."""

    mesh: MeshData
    size: tuple[float, float, float]  # (w, d, h) metres of the canonical bounding box


def normalize_loaded(loaded: Any, *, rotation: np.ndarray | None = None, size: Sequence[float] | None = None,
                     scale: float | None = None) -> Normalized:
    """Flatten a trimesh Trimesh/Scene and normalise it (:func:`normalize_arrays`)."""
    v, f, c = flatten_geometry(loaded)
    if len(f) == 0 and len(getattr(loaded, "geometry", {}) or {}) > 0:
        raise MeshRejected("no triangles: the file holds only lines or points")
    return normalize_arrays(v, f, c, rotation=rotation, size=size, scale=scale)


def normalize_arrays(vertices: np.ndarray, faces: np.ndarray, colors: np.ndarray, *, rotation: np.ndarray | None = None,
                     size: Sequence[float] | None = None, scale: float | None = None) -> Normalized:
    """Validate, compact, rotate/scale into the canonical frame; raises :class:`MeshRejected`.

    vertices (V, 3) float, faces (F, 3) int, colors (F, 3) uint8.
    """
    v, f, c = np.asarray(vertices, dtype=np.float64), np.asarray(faces, dtype=np.int64), np.asarray(colors)
    reason = validate_mesh(v, f)
    if reason:
        raise MeshRejected(reason)
    v, f, c = compact(v, f, c)
    if len(f) == 0:
        raise MeshRejected("empty mesh: every triangle repeats a vertex")
    if rotation is not None:
        reason = validate_mesh(v @ np.asarray(rotation, dtype=np.float64).T, f)
        if reason:
            raise MeshRejected(reason)
    v = to_canonical(v, rotation=rotation, size=size, scale=scale)
    if not np.all(np.isfinite(v)):
        raise MeshRejected("invalid mesh: non-finite coordinates after scaling")
    ext = v.max(0) - v.min(0)
    mesh = MeshData(vertices=v.astype(np.float32), faces=f.astype(np.int32), face_colors=np.ascontiguousarray(c, dtype=np.uint8))
    return Normalized(mesh=mesh, size=(float(ext[0]), float(ext[1]), float(ext[2])))


# --------------------------------------------------------------------------------------------
# Support surfaces
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _FaceBounds:
    """Per-face bounds used by clearance queries: (F,) float64 arrays."""

    zmin: np.ndarray
    xmin: np.ndarray
    xmax: np.ndarray
    ymin: np.ndarray
    ymax: np.ndarray

    @staticmethod
    def of(tri: np.ndarray) -> "_FaceBounds":
        return _FaceBounds(tri[:, :, 2].min(1), tri[:, :, 0].min(1), tri[:, :, 0].max(1),
                           tri[:, :, 1].min(1), tri[:, :, 1].max(1))


def _clearance(polygon, tri: np.ndarray, fb: _FaceBounds, height: float, band: float,
               cover: float = CLEARANCE_COVER) -> float | None:
    """Free height above a surface at ``height`` with outline ``polygon``, or None.

    Faces starting more than ``band`` above the surface with their centroid over the polygon are
    taken from the lowest up; the clearance is where their projected (x-y) area first reaches
    ``cover`` times the polygon's area: a shelf board above counts, a pillow on a bed or a tap
    over a basin does not. None when nothing above covers that much.
    """
    import shapely

    x0, y0, x1, y1 = polygon.bounds
    above = np.nonzero((fb.zmin > height + band) & (fb.xmax > x0) & (fb.xmin < x1) & (fb.ymax > y0) & (fb.ymin < y1))[0]
    if len(above) == 0:
        return None
    t = tri[above][:, :, :2]
    centroid = t.mean(axis=1)
    inside = shapely.contains_xy(polygon, centroid[:, 0], centroid[:, 1])
    if not inside.any():
        return None
    above, t = above[inside], t[inside]
    e1, e2 = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]
    projected = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    order = np.argsort(fb.zmin[above], kind="stable")
    covered = np.cumsum(projected[order])
    k = int(np.searchsorted(covered, cover * polygon.area))
    if k >= len(covered):
        return None
    return float(fb.zmin[above[order[k]]] - height)


def _large_patches(faces: np.ndarray, tri: np.ndarray, area: np.ndarray, min_area: float) -> np.ndarray:
    """The faces (indices) of ``faces`` in edge/vertex-connected patches of at least ``min_area``.

    Connectivity uses corner positions quantised to 0.1 mm, so meshes whose vertices were split
    (per UV or normal) still connect.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(faces)
    if n <= 1:
        return faces if n and area[faces].sum() >= min_area else faces[:0]
    q = np.round(tri[faces][:, :, :2].reshape(-1, 2) / 1e-4).astype(np.int64)
    key = (q[:, 0] << 32) ^ (q[:, 1] & 0xFFFFFFFF)
    _, corner_id = np.unique(key, return_inverse=True)
    corner_id = corner_id.reshape(-1)
    m = int(corner_id.max()) + 1
    # bipartite graph: face nodes 0..n-1, corner nodes n..n+m-1
    rows = np.repeat(np.arange(n), 3)
    graph = coo_matrix((np.ones(3 * n, dtype=np.int8), (rows, corner_id + n)), shape=(n + m, n + m))
    _, labels_all = connected_components(graph, directed=False)
    labels = labels_all[:n]
    patch_area = np.bincount(labels, weights=area[faces])
    return faces[patch_area[labels] >= min_area]


def extract_supports(mesh: MeshData, *, min_area: float = 0.01, min_fraction: float = 0.03, min_height: float = 0.05,
                     max_tilt_deg: float = 10.0, height_tol: float = 0.01, min_clearance: float = 0.05,
                     max_surfaces: int = 8, simplify: float = 0.005,
                     max_union_faces: int = 20000) -> tuple[SupportSurface, ...]:
    """Horizontal upward surfaces of a canonical mesh that objects can rest on.

    Up-facing faces (normal within ``max_tilt_deg`` of +z) are clustered by height (a new cluster
    starts where sorted heights jump by more than ``height_tol``); clusters with enough area (at
    least ``min_area`` m^2 and ``min_fraction`` of the footprint's bounding box) and at least
    ``min_height`` above the base become surfaces. Each cluster's triangles are unioned (shapely)
    into polygons; every polygon part with enough area becomes a :class:`SupportSurface`
    (exterior ring, simplified by ``simplify`` metres, counter-clockwise). ``clearance`` is the
    free height above (see :func:`_clearance`: the height where faces above cover half the
    surface; ``None`` if they never do); surfaces with less than ``min_clearance`` are dropped
    (enclosed or covered). At most ``max_surfaces``, largest first, returned by height.

    Cost is bounded: connected patches of a cluster smaller than ``min_area`` (leaves of a plant)
    are dropped before the polygon union, only the ``2 * max_surfaces`` largest clusters are
    unioned, and at most ``max_union_faces`` triangles per cluster.
    """
    import shapely

    v = mesh.vertices.astype(np.float64)
    f = mesh.faces.astype(np.int64)
    if len(f) == 0:
        return ()
    ext = v.max(0) - v.min(0)
    min_area = max(min_area, min_fraction * float(ext[0] * ext[1]))
    tri = v[f]  # (F, 3, 3)
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(cross, axis=1)
    area = 0.5 * norm
    nz = np.divide(cross[:, 2], norm, out=np.zeros_like(norm), where=norm > 0)
    zc = tri[:, :, 2].mean(1)
    up = (nz >= np.cos(np.radians(max_tilt_deg))) & (area > 0) & (zc >= min_height)
    idx = np.nonzero(up)[0]
    if len(idx) == 0:
        return ()
    order = idx[np.argsort(zc[idx], kind="stable")]
    z_sorted = zc[order]
    breaks = np.nonzero(np.diff(z_sorted) > height_tol)[0] + 1
    starts = np.concatenate([[0], breaks])
    ends = np.concatenate([breaks, [len(order)]])
    cluster_area = np.add.reduceat(area[order], starts)
    candidates = [(s, e) for s, e, a in zip(starts, ends, cluster_area) if a >= min_area]
    if not candidates:
        return ()
    fb = _FaceBounds.of(tri)
    surfaces: list[tuple[float, SupportSurface]] = []
    # largest clusters first, at most 2 * max_surfaces of them (a bounded amount of polygon work)
    candidates.sort(key=lambda se: -float(area[order[se[0]:se[1]]].sum()))
    for s, e in candidates[:2 * max_surfaces]:
        faces_c = _large_patches(order[s:e], tri, area, min_area)
        if len(faces_c) == 0:
            continue
        if len(faces_c) > max_union_faces:  # keep the largest triangles: the outline barely changes
            faces_c = faces_c[np.argsort(-area[faces_c], kind="stable")[:max_union_faces]]
        height = float(np.average(zc[faces_c], weights=area[faces_c]))
        polys = shapely.polygons(tri[faces_c][:, :, :2])
        merged = shapely.union_all(polys)
        parts = [merged] if merged.geom_type == "Polygon" else list(getattr(merged, "geoms", []))
        for part in parts:
            if part.geom_type != "Polygon" or part.area < min_area:
                continue
            outline = shapely.Polygon(part.exterior).simplify(simplify, preserve_topology=True)
            if outline.is_empty or outline.area < min_area:
                continue
            outline = shapely.geometry.polygon.orient(outline, 1.0)
            clearance = _clearance(outline, tri, fb, height, height_tol)
            if clearance is not None and clearance < min_clearance:
                continue
            coords = tuple((round(float(x), 6), round(float(y), 6)) for x, y in np.asarray(outline.exterior.coords)[:-1])
            surfaces.append((float(part.area), SupportSurface(height=height, polygon=coords, clearance=clearance)))
    surfaces.sort(key=lambda t: -t[0])
    kept = [s for _, s in surfaces[:max_surfaces]]
    kept.sort(key=lambda s: (s.height, s.polygon))
    return tuple(kept)


def support_at_height(mesh: MeshData, height: float, *, band: float = 0.03, min_fraction: float = 0.3,
                      margin: float = 0.9) -> SupportSurface:
    """A support surface at a given height (e.g. Sweet Home 3D's ``dropOnTopElevation``).

    The polygon is the convex hull of the vertices within ``band`` metres of ``height`` when that
    covers at least ``min_fraction`` of the footprint, else the bounding-box footprint shrunk to
    ``margin``. ``clearance`` as in :func:`extract_supports`, ignoring faces less than ``band``
    above ``height`` (the padded or curved surface itself).
    """
    import shapely

    v = mesh.vertices.astype(np.float64)
    lo, hi = v.min(0), v.max(0)
    box = shapely.box(lo[0] * margin, lo[1] * margin, hi[0] * margin, hi[1] * margin)
    near = v[np.abs(v[:, 2] - height) <= band]
    poly = box
    if len(near) >= 3:
        hull = shapely.MultiPoint(near[:, :2]).convex_hull
        if hull.geom_type == "Polygon" and hull.area >= min_fraction * box.area:
            poly = hull.simplify(0.005, preserve_topology=True)
    poly = shapely.geometry.polygon.orient(poly, 1.0)
    tri = v[mesh.faces.astype(np.int64)]
    # faces just above the given height are the surface itself (cushions, a mattress's bulge)
    clearance = _clearance(poly, tri, _FaceBounds.of(tri), float(height), band)
    coords = tuple((round(float(x), 6), round(float(y), 6)) for x, y in np.asarray(poly.exterior.coords)[:-1])
    return SupportSurface(height=float(height), polygon=coords, clearance=clearance)
