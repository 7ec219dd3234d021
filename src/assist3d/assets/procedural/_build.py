"""Mesh-building helpers of the procedural library.

A family collects closed primitives (boxes, cylinders, frusta, ellipsoids, tori, lathe and
extrusion solids, manifold CSG results) into a :class:`MeshBuilder`, each with one colour, and
calls :meth:`MeshBuilder.finish` to get a :class:`Shape` in the canonical frame. Every primitive is
closed with outward winding, and parts never share vertices, so the concatenation is watertight
(each edge used by exactly two faces) and consistently wound even where parts overlap.

Unit primitives are built once (trimesh) and cached; a part is a scaled and moved copy of one, so
building an asset costs a few hundred microseconds per part.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import Sequence

import numpy as np
import trimesh
from trimesh import creation

from ...core.contracts import MeshData, SupportSurface

Color = tuple[int, int, int]
Vec3 = Sequence[float]


# ------------------------------------------------------------------------------------ rotations


def rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=np.float64)


def rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], dtype=np.float64)


def rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=np.float64)


def align_z(direction: Vec3) -> np.ndarray:
    """(3, 3) rotation taking +z onto the unit vector of ``direction``."""
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    z = np.array([0.0, 0.0, 1.0])
    v = np.cross(z, d)
    c = float(d @ z)
    if np.linalg.norm(v) < 1e-12:
        return np.eye(3) if c > 0 else rot_x(np.pi)
    k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + k + k @ k * (1.0 / (1.0 + c))


# ------------------------------------------------------------------------------------ unit primitives


def _arrays(m: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    v = np.asarray(m.vertices, dtype=np.float64).copy()
    f = np.asarray(m.faces, dtype=np.int64).copy()
    v.flags.writeable = False
    f.flags.writeable = False
    return v, f


@lru_cache(maxsize=None)
def unit_box() -> tuple[np.ndarray, np.ndarray]:
    """Unit cube centred on the origin."""
    return _arrays(creation.box((1.0, 1.0, 1.0)))


@lru_cache(maxsize=None)
def unit_cylinder(sections: int) -> tuple[np.ndarray, np.ndarray]:
    """Radius 1, z from 0 to 1."""
    v, f = _arrays(creation.cylinder(radius=1.0, height=1.0, sections=sections))
    v = v + np.array([0.0, 0.0, 0.5])
    v.flags.writeable = False
    return v, f


@lru_cache(maxsize=None)
def unit_cone(sections: int) -> tuple[np.ndarray, np.ndarray]:
    """Radius 1 at z = 0, apex at z = 1."""
    return _arrays(creation.cone(radius=1.0, height=1.0, sections=sections))


@lru_cache(maxsize=None)
def unit_sphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    return _arrays(creation.icosphere(subdivisions=subdivisions, radius=1.0))


# ------------------------------------------------------------------------------------ colours


def jitter(color: Sequence[float], rng: np.random.Generator, amount: float = 12.0) -> Color:
    c = np.clip(np.asarray(color, dtype=np.float64) + rng.normal(0.0, amount, 3), 0, 255)
    return (int(c[0]), int(c[1]), int(c[2]))


_WOOD = ((156, 110, 66), (120, 80, 45), (196, 160, 110), (90, 60, 35), (214, 186, 140), (70, 45, 30), (170, 120, 80))
_METAL = ((180, 180, 185), (120, 122, 128), (60, 62, 66), (200, 195, 180), (35, 35, 38), (150, 140, 120))
_FABRIC = ((120, 130, 150), (160, 60, 55), (70, 90, 70), (200, 190, 170), (60, 60, 70), (150, 120, 90),
           (90, 110, 140), (180, 150, 160), (110, 70, 90), (210, 205, 195), (50, 70, 110))
_PLASTIC = ((230, 230, 230), (30, 30, 32), (200, 60, 50), (50, 110, 190), (240, 200, 60), (70, 160, 90),
            (240, 140, 40), (150, 80, 170), (120, 200, 210))
_CERAMIC = ((240, 238, 230), (220, 215, 200), (180, 200, 210), (200, 170, 150), (150, 170, 140), (60, 80, 110),
            (230, 220, 190), (170, 60, 50))
_PAINT = ((235, 235, 230), (245, 240, 225), (200, 205, 210), (60, 65, 70), (180, 190, 170), (150, 170, 190),
          (225, 215, 190))
_LEAF = ((60, 120, 50), (40, 95, 45), (90, 140, 60), (50, 110, 80), (110, 150, 70))


def as_rgb(color: Sequence[float]) -> Color:
    """A colour as a tuple of three ints (e.g. from a numpy expression)."""
    return (int(color[0]), int(color[1]), int(color[2]))


def _pick(palette: Sequence[Color], rng: np.random.Generator, amount: float) -> Color:
    return jitter(palette[int(rng.integers(len(palette)))], rng, amount)


def wood(rng: np.random.Generator) -> Color:
    return _pick(_WOOD, rng, 10.0)


def metal(rng: np.random.Generator) -> Color:
    return _pick(_METAL, rng, 6.0)


def fabric(rng: np.random.Generator) -> Color:
    return _pick(_FABRIC, rng, 14.0)


def plastic(rng: np.random.Generator) -> Color:
    return _pick(_PLASTIC, rng, 10.0)


def ceramic(rng: np.random.Generator) -> Color:
    return _pick(_CERAMIC, rng, 8.0)


def paint(rng: np.random.Generator) -> Color:
    return _pick(_PAINT, rng, 6.0)


def leaf(rng: np.random.Generator) -> Color:
    return _pick(_LEAF, rng, 12.0)


def any_color(rng: np.random.Generator) -> Color:
    c = rng.integers(20, 236, 3)
    return (int(c[0]), int(c[1]), int(c[2]))


def material(rng: np.random.Generator) -> Color:
    """A furniture body colour: wood, paint or metal."""
    k = rng.random()
    return wood(rng) if k < 0.5 else paint(rng) if k < 0.8 else metal(rng)


DARK: Color = (25, 25, 28)
SCREEN: Color = (15, 18, 24)
WHITE: Color = (238, 238, 235)
GLASS: Color = (170, 195, 205)
MIRROR: Color = (200, 210, 215)


# ------------------------------------------------------------------------------------ supports


def rect_support(x0: float, x1: float, y0: float, y1: float, height: float, *, inset: float = 0.02,
                 clearance: float | None = None) -> SupportSurface:
    """A rectangular support surface, inset from its edges, counter-clockwise."""
    a, b = min(x0, x1) + inset, max(x0, x1) - inset
    c, d = min(y0, y1) + inset, max(y0, y1) - inset
    if b <= a or d <= c:
        raise ValueError(f"support rectangle too small after inset {inset}: x {x0}..{x1}, y {y0}..{y1}")
    poly = ((a, c), (b, c), (b, d), (a, d))
    return SupportSurface(float(height), tuple((float(x), float(y)) for x, y in poly),
                          None if clearance is None else float(clearance))


def disc_support(cx: float, cy: float, radius: float, height: float, *, inset: float = 0.02, n: int = 12,
                 clearance: float | None = None) -> SupportSurface:
    """A regular ``n``-gon inscribed in a circle of ``radius - inset``, counter-clockwise."""
    r = radius - inset
    if r <= 0:
        raise ValueError(f"disc support radius {radius} too small for inset {inset}")
    t = np.arange(n) * (2 * np.pi / n)
    poly = tuple((float(cx + r * np.cos(a)), float(cy + r * np.sin(a))) for a in t)
    return SupportSurface(float(height), poly, None if clearance is None else float(clearance))


# ------------------------------------------------------------------------------------ builder


@dataclass(frozen=True)
class Shape:
    """What a family returns: a canonical-frame mesh plus its semantic facts."""

    mesh: MeshData
    class_name: str
    size: tuple[float, float, float]
    supports: tuple[SupportSurface, ...] = ()
    elevation: float = 0.0
    extra: dict = field(default_factory=dict)


class MeshBuilder:
    """Collects coloured closed parts; :meth:`finish` concatenates and normalises them."""

    def __init__(self) -> None:
        self._verts: list[np.ndarray] = []
        self._faces: list[np.ndarray] = []
        self._colors: list[np.ndarray] = []
        self._count = 0

    # ---------------------------------------------------------------- low level

    def add(self, vertices: np.ndarray, faces: np.ndarray, color: Color | np.ndarray) -> None:
        """Add a closed part: vertices (V, 3), faces (F, 3), one colour (3,) or per-face colours (F, 3)."""
        v = np.asarray(vertices, dtype=np.float64)
        f = np.asarray(faces, dtype=np.int64)
        if len(f) == 0:
            return
        c = np.asarray(color, dtype=np.uint8)
        c = np.broadcast_to(c, (len(f), 3)) if c.ndim == 1 else c
        self._verts.append(v)
        self._faces.append(f + self._count)
        self._colors.append(c)
        self._count += len(v)

    def add_unit(self, unit: tuple[np.ndarray, np.ndarray], linear: np.ndarray, offset: Vec3, color: Color) -> None:
        """Add ``linear @ v + offset`` of a unit primitive; a mirroring map flips the winding back."""
        v, f = unit
        v2 = v @ np.asarray(linear, dtype=np.float64).T + np.asarray(offset, dtype=np.float64)
        if np.linalg.det(linear) < 0:
            f = f[:, ::-1]
        self.add(v2, f, color)

    def add_trimesh(self, mesh: trimesh.Trimesh, color: Color, *, linear: np.ndarray | None = None,
                    offset: Vec3 = (0.0, 0.0, 0.0)) -> None:
        unit = (np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64))
        self.add_unit(unit, np.eye(3) if linear is None else linear, offset, color)

    # ---------------------------------------------------------------- primitives

    def box(self, size: Vec3, center: Vec3, color: Color, *, rot: np.ndarray | None = None) -> None:
        """An axis-aligned (or ``rot``-rotated about its centre) box of ``size`` (x, y, z)."""
        lin = np.diag(np.asarray(size, dtype=np.float64))
        if rot is not None:
            lin = rot @ lin
        self.add_unit(unit_box(), lin, center, color)

    def slab(self, x0: float, x1: float, y0: float, y1: float, z0: float, z1: float, color: Color) -> None:
        """An axis-aligned box given by its extents."""
        self.box((x1 - x0, y1 - y0, z1 - z0), ((x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2), color)

    def cylinder(self, radius: float, height: float, base: Vec3, color: Color, *, sections: int = 16,
                 top_radius: float | None = None, rot: np.ndarray | None = None, radius_y: float | None = None) -> None:
        """A z-axis cylinder (or frustum when ``top_radius`` differs) whose base centre is ``base``.

        ``rot`` turns it about its base centre; ``radius_y`` makes an elliptic section.
        """
        v, f = unit_cylinder(sections)
        if top_radius is not None and top_radius != radius:
            v = v.copy()
            top = v[:, 2] > 0.5
            v[top, :2] *= max(top_radius, 1e-4) / radius
        lin = np.diag([radius, radius if radius_y is None else radius_y, height])
        if rot is not None:
            lin = rot @ lin
        self.add_unit((v, f), lin, base, color)

    def cone(self, radius: float, height: float, base: Vec3, color: Color, *, sections: int = 16,
             rot: np.ndarray | None = None) -> None:
        lin = np.diag([radius, radius, height])
        if rot is not None:
            lin = rot @ lin
        self.add_unit(unit_cone(sections), lin, base, color)

    def bar(self, p0: Vec3, p1: Vec3, radius: float, color: Color, *, sections: int = 8) -> None:
        """A round bar (cylinder) from point ``p0`` to point ``p1``."""
        a = np.asarray(p0, dtype=np.float64)
        d = np.asarray(p1, dtype=np.float64) - a
        length = float(np.linalg.norm(d))
        self.cylinder(radius, length, a, color, sections=sections, rot=align_z(d))

    def beam(self, p0: Vec3, p1: Vec3, width: float, thickness: float, color: Color) -> None:
        """A square-section bar from ``p0`` to ``p1`` (width along the horizontal normal)."""
        a = np.asarray(p0, dtype=np.float64)
        d = np.asarray(p1, dtype=np.float64) - a
        length = float(np.linalg.norm(d))
        lin = align_z(d) @ np.diag([width, thickness, length])
        self.add_unit(unit_box(), lin, a + d / 2, color)

    def ellipsoid(self, radii: Vec3, center: Vec3, color: Color, *, subdivisions: int = 1,
                  rot: np.ndarray | None = None) -> None:
        lin = np.diag(np.asarray(radii, dtype=np.float64))
        if rot is not None:
            lin = rot @ lin
        self.add_unit(unit_sphere(subdivisions), lin, center, color)

    def torus(self, major: float, minor: float, center: Vec3, color: Color, *, sections: int = 16,
              minor_sections: int = 8, rot: np.ndarray | None = None) -> None:
        """A torus around the z axis (``rot`` turns it), centred on ``center``."""
        m = creation.torus(major_radius=major, minor_radius=minor, major_sections=sections,
                           minor_sections=minor_sections)
        self.add_trimesh(m, color, linear=np.eye(3) if rot is None else rot, offset=center)

    def capsule(self, radius: float, length: float, center: Vec3, color: Color, *, rot: np.ndarray | None = None,
                count: tuple[int, int] = (10, 10)) -> None:
        """A capsule along z of total length ``length`` (>= 2 radius), centred on ``center``."""
        m = creation.capsule(height=max(length - 2 * radius, 1e-4), radius=radius, count=list(count))
        self.add_trimesh(m, color, linear=np.eye(3) if rot is None else rot, offset=center)

    def lathe(self, profile: Sequence[Sequence[float]], color: Color, *, base: Vec3 = (0.0, 0.0, 0.0),
              sections: int = 24, rot: np.ndarray | None = None) -> None:
        """A solid of revolution about z from a (radius, z) profile.

        The profile is closed through the axis: its first and last points are put on the axis
        (radius 0) if they are not, so the solid is watertight; its direction is fixed so the
        normals face outward.
        """
        p = np.asarray(profile, dtype=np.float64)
        if p[0, 0] != 0.0:
            p = np.vstack([[0.0, p[0, 1]], p])
        if p[-1, 0] != 0.0:
            p = np.vstack([p, [0.0, p[-1, 1]]])
        # signed area of the closed (r, z) polygon: positive = counter-clockwise = outward normals
        area = 0.5 * float(np.sum(p[:-1, 0] * p[1:, 1] - p[1:, 0] * p[:-1, 1]) + p[-1, 0] * p[0, 1] - p[0,
                0] * p[-1, 1])
        if area < 0:
            p = p[::-1]
        m = creation.revolve(p, sections=sections)
        self.add_trimesh(m, color, linear=np.eye(3) if rot is None else rot, offset=base)

    def extrude(self, polygon, height: float, color: Color, *, offset: Vec3 = (0.0, 0.0, 0.0),
                rot: np.ndarray | None = None) -> None:
        """Extrude a shapely polygon (or (n, 2) ring) along z from 0 to ``height``, then ``rot`` and move."""
        from shapely.geometry import Polygon

        poly = polygon if hasattr(polygon, "exterior") else Polygon(np.asarray(polygon, dtype=np.float64))
        m = creation.extrude_polygon(poly, height)
        self.add_trimesh(m, color, linear=np.eye(3) if rot is None else rot, offset=offset)

    def manifold(self, solid, colors: dict[int, Color] | Color, default: Color | None = None) -> None:
        """Add a manifold3d solid. ``colors`` maps ``original_id()`` of its inputs to colours."""
        m = solid.to_mesh()
        v = np.asarray(m.vert_properties, dtype=np.float64)[:, :3]
        f = np.asarray(m.tri_verts, dtype=np.int64)
        if isinstance(colors, tuple):
            self.add(v, f, colors)
            return
        fallback = default if default is not None else next(iter(colors.values()))
        c = np.zeros((len(f), 3), dtype=np.uint8)
        c[:] = fallback
        run_index = np.asarray(m.run_index, dtype=np.int64) // 3
        for k, oid in enumerate(np.asarray(m.run_original_id, dtype=np.int64)):
            if int(oid) in colors:
                c[run_index[k]:run_index[k + 1]] = colors[int(oid)]
        self.add(v, f, c)

    # ---------------------------------------------------------------- result

    def finish(self, class_name: str, *, supports: Sequence[SupportSurface] = (), elevation: float = 0.0,
               extra: dict | None = None) -> Shape:
        """Concatenate the parts, move them to the canonical frame and shift the supports alike."""
        if not self._faces:
            raise ValueError(f"{class_name}: no parts were added")
        v = np.concatenate(self._verts)
        f = np.concatenate(self._faces)
        c = np.concatenate(self._colors)
        lo, hi = v.min(0), v.max(0)
        shift = np.array([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
        v32 = (v + shift).astype(np.float32)
        # recompute the box on the float32 values so the recorded size matches the stored mesh
        lo32, hi32 = v32.min(0).astype(np.float64), v32.max(0).astype(np.float64)
        size = tuple(float(s) for s in (hi32 - lo32))
        moved = tuple(
            SupportSurface(float(s.height + shift[2]),
                           tuple((float(x + shift[0]), float(y + shift[1])) for x, y in s.polygon), s.clearance)
            for s in supports)
        mesh = MeshData(vertices=v32, faces=f.astype(np.int32), face_colors=np.ascontiguousarray(c, dtype=np.uint8))
        return Shape(mesh=mesh, class_name=class_name, size=size, supports=moved, elevation=float(elevation),
                     extra=dict(extra or {}))
