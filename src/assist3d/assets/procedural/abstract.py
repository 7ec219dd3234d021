"""Abstract shapes for geometric variety: superquadrics, CSG compositions, convex hulls,
extrusions, revolved profiles, rings, blobs and stacked sculptures."""

from __future__ import annotations

import manifold3d as mf
import numpy as np
from shapely.geometry import Polygon
from shapely.ops import unary_union

from ._build import MeshBuilder, Shape, any_color, ceramic, metal, plastic, rot_x, rot_y, rot_z, unit_sphere
from ._parts import choice, u
from ._registry import family


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    return rot_z(rng.uniform(0, 2 * np.pi)) @ rot_y(rng.uniform(0, np.pi)) @ rot_x(rng.uniform(0, 2 * np.pi))


def _color(rng: np.random.Generator):
    k = rng.random()
    return plastic(rng) if k < 0.4 else ceramic(rng) if k < 0.6 else metal(rng) if k < 0.75 else any_color(rng)


@family("superquadric", ("obj",), weight=1.5)
def superquadric(rng: np.random.Generator) -> Shape:
    """A superellipsoid: the icosphere's directions pushed radially onto the surface
    ``((|x/a|^(2/e2) + |y/b|^(2/e2))^(e2/e1) + |z/c|^(2/e1)) = 1`` (a radial map keeps it closed
    and outward-wound)."""
    b = MeshBuilder()
    e1, e2 = u(rng, 0.25, 1.8), u(rng, 0.25, 1.8)
    radii = rng.uniform(0.03, 0.15, 3)
    v, f = unit_sphere(3)
    ax = np.abs(v) / radii + 1e-12
    F = (ax[:, 0] ** (2 / e2) + ax[:, 1] ** (2 / e2)) ** (e2 / e1) + ax[:, 2] ** (2 / e1)
    pts = v * (F ** (-e1 / 2))[:, None]
    if rng.random() < 0.5:
        pts = pts @ _random_rotation(rng).T
    b.add(pts, f, _color(rng))
    return b.finish("superquadric", extra={"e1": round(e1, 4), "e2": round(e2, 4)})


def _primitive(rng: np.random.Generator, scale: float) -> mf.Manifold:
    kind = choice(rng, ("cube", "cylinder", "sphere"))
    s = rng.uniform(0.4, 1.0, 3) * scale
    if kind == "cube":
        m = mf.Manifold.cube(tuple(float(x) for x in s), True)
    elif kind == "cylinder":
        m = mf.Manifold.cylinder(float(s[2]), float(s[0] / 2), float(s[0] / 2 * rng.uniform(0.3, 1.0)), 20, True)
    else:
        m = mf.Manifold.sphere(float(s[0] / 2), 20).scale((1.0, float(s[1] / s[0]), float(s[2] / s[0])))
    ang = rng.uniform(0, 360, 3) if rng.random() < 0.5 else np.zeros(3)
    return m.rotate(tuple(float(a) for a in ang)).translate(tuple(float(x) for x in rng.normal(0, scale * 0.25, 3)))


def _has_slivers(solid: mf.Manifold) -> bool:
    """Whether a boolean result holds near-zero-area triangles (they would break validity checks)."""
    m = solid.to_mesh()
    v = np.asarray(m.vert_properties, dtype=np.float64)[:, :3]
    t = v[np.asarray(m.tri_verts, dtype=np.int64)]
    area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    return bool(area.min() < 1e-9)


@family("csg_shape", ("obj",), weight=1.5)
def csg_shape(rng: np.random.Generator) -> Shape:
    """Boolean unions, differences and intersections of random boxes, cylinders and spheres."""
    b = MeshBuilder()
    scale = u(rng, 0.08, 0.3)
    colors: dict[int, tuple[int, int, int]] = {}
    base = _primitive(rng, scale).as_original()
    colors[base.original_id()] = _color(rng)
    solid = base
    for _ in range(int(rng.integers(2, 5))):
        p = _primitive(rng, scale * u(rng, 0.5, 1.0)).as_original()
        colors[p.original_id()] = _color(rng)
        op = rng.random()
        trial = solid + p if op < 0.5 else solid - p if op < 0.85 else solid ^ p
        # keep one connected solid with no internal voids (a void is a component with negative volume)
        if (trial.num_tri() > 0 and trial.volume() > 0.05 * solid.volume() and len(trial.decompose()) == 1
                and not _has_slivers(trial)):
            solid = trial
    b.manifold(solid, colors)
    return b.finish("csg shape")


@family("convex_shape", ("obj",))
def convex_shape(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    n = int(rng.integers(10, 40))
    pts = rng.normal(size=(n, 3)) * rng.uniform(0.02, 0.12, 3)
    hull = mf.Manifold.hull_points([tuple(float(x) for x in p) for p in pts])
    b.manifold(hull, _color(rng))
    return b.finish("convex shape")


def _star(rng: np.random.Generator, r: float) -> Polygon:
    n = int(rng.integers(5, 14))
    t = np.sort(rng.uniform(0, 2 * np.pi, n))
    rr = r * rng.uniform(0.35, 1.0, n)
    return Polygon(np.column_stack([np.cos(t) * rr, np.sin(t) * rr]))


@family("extruded_shape", ("obj",))
def extruded_shape(rng: np.random.Generator) -> Shape:
    """A random star polygon or union of rectangles, extruded; standing or lying on a side."""
    b = MeshBuilder()
    r = u(rng, 0.04, 0.15)
    if rng.random() < 0.5:
        poly = _star(rng, r)
    else:
        rects = []
        for _ in range(int(rng.integers(2, 5))):
            c = rng.normal(0, r * 0.4, 2)
            s = rng.uniform(0.2, 1.0, 2) * r
            rects.append(Polygon([(c[0] - s[0], c[1] - s[1]), (c[0] + s[0], c[1] - s[1]), (c[0] + s[0], c[1] + s[1]),
                                  (c[0] - s[0], c[1] + s[1])]))
        poly = unary_union(rects)
        if poly.geom_type != "Polygon":
            poly = max(poly.geoms, key=lambda g: g.area)
    if not poly.is_valid:
        poly = poly.buffer(0)
        if poly.geom_type != "Polygon":
            poly = max(poly.geoms, key=lambda g: g.area)
    h = u(rng, 0.01, 0.3)
    b.extrude(poly, h, _color(rng), rot=rot_x(np.pi / 2) if rng.random() < 0.3 else None)
    return b.finish("extruded shape")


@family("revolved_shape", ("obj",))
def revolved_shape(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    n = int(rng.integers(3, 9))
    zs = np.sort(rng.uniform(0, u(rng, 0.05, 0.35), n))
    zs[0] = 0.0
    zs = np.maximum.accumulate(zs + np.arange(n) * 1e-3)
    rs = rng.uniform(0.01, 0.12, n)
    b.lathe(list(zip(rs.tolist(), zs.tolist())), _color(rng), sections=int(choice(rng, (5, 6, 8, 12, 24))))
    return b.finish("revolved shape")


@family("ring_shape", ("obj",), weight=0.5)
def ring_shape(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    R = u(rng, 0.03, 0.12)
    r = R * u(rng, 0.1, 0.45)
    rot = rot_x(np.pi / 2) if rng.random() < 0.4 else None
    b.torus(R, r, (0, 0, 0), _color(rng), sections=int(choice(rng, (6, 12, 24))), minor_sections=int(choice(rng,
            (4, 8))),
            rot=rot)
    return b.finish("ring")


@family("blob", ("obj",))
def blob(rng: np.random.Generator) -> Shape:
    """An icosphere displaced radially by a few random low-frequency waves (star-shaped, so valid)."""
    b = MeshBuilder()
    v, f = unit_sphere(3)
    radius = np.ones(len(v))
    for _ in range(int(rng.integers(2, 6))):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        radius += rng.uniform(0.05, 0.3) * np.sin(rng.integers(1, 5) * np.arccos(np.clip(v @ axis, -1, 1))
                                                  + rng.uniform(0, 2 * np.pi))
    radius = np.maximum(radius, 0.3)
    b.add(v * radius[:, None] * rng.uniform(0.03, 0.12, 3), f, _color(rng))
    return b.finish("blob")


@family("sculpture", ("obj",), weight=0.7)
def sculpture(rng: np.random.Generator) -> Shape:
    """A small stack of primitives on a plinth: an ornament."""
    b = MeshBuilder()
    s = u(rng, 0.05, 0.12)
    b.slab(-s, s, -s, s, 0, s * 0.4, _color(rng))
    z = s * 0.4
    for _ in range(int(rng.integers(2, 5))):
        kind = rng.random()
        c = _color(rng)
        h = s * u(rng, 0.3, 1.2)
        if kind < 0.35:
            w = s * u(rng, 0.3, 0.9)
            b.box((w, w, h), (0, 0, z + h / 2), c, rot=rot_z(rng.uniform(0, np.pi)))
        elif kind < 0.65:
            b.cylinder(s * u(rng, 0.2, 0.8), h, (0, 0, z), c, sections=16, top_radius=s * u(rng, 0.1, 0.8))
        else:
            rr = s * u(rng, 0.3, 0.8)
            b.ellipsoid((rr, rr, h / 2), (0, 0, z + h / 2), c, subdivisions=2)
        z += h * 0.95
    return b.finish("sculpture")
