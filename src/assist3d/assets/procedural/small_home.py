"""Small household objects: tableware, kitchenware, containers, books, boxes, lamps, plants, food."""

from __future__ import annotations

import numpy as np

from ._build import (DARK, GLASS, WHITE, MeshBuilder, Shape, any_color, as_rgb, ceramic, fabric, leaf, material, metal,
                     plastic, rect_support, rot_x, rot_y, rot_z, wood)
from ._parts import choice, flower_pot, foliage, u
from ._registry import family


def _vessel(b: MeshBuilder, rng: np.random.Generator, outer: list[tuple[float, float]], wall: float, color,
            *, sections: int = 24) -> None:
    """An open vessel from an outer (radius, z) profile going up from the base: the inner wall
    follows it ``wall`` inside and the floor is ``wall`` thick."""
    o = np.asarray(outer, dtype=np.float64)
    inner = o[::-1].copy()
    inner[:, 0] = np.maximum(inner[:, 0] - wall, 1e-3)
    inner[-1, 1] = max(inner[-1, 1], o[0, 1]) + wall
    inner = inner[inner[:, 1] >= o[0, 1] + wall - 1e-9]
    prof = [(float(r), float(z)) for r, z in o] + [(float(r), float(z)) for r, z in inner] + [(0.0, float(o[0,
            1] + wall))]
    b.lathe(prof, color, sections=sections)


@family("cup", ("obj",))
def cup(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.03, 0.045), u(rng, 0.07, 0.14)
    c = ceramic(rng) if rng.random() < 0.5 else (GLASS if rng.random() < 0.5 else plastic(rng))
    _vessel(b, rng, [(r * u(rng, 0.65, 1.0), 0.0), (r, h)], 0.004, c, sections=20)
    return b.finish("cup")


@family("mug", ("obj",))
def mug(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.035, 0.05), u(rng, 0.08, 0.12)
    c = ceramic(rng) if rng.random() < 0.6 else any_color(rng)
    _vessel(b, rng, [(r, 0.0), (r * u(rng, 0.95, 1.08), h)], 0.005, c, sections=20)
    hr = h * u(rng, 0.25, 0.35)
    b.torus(hr, 0.007, (r + hr * 0.55, 0, h * 0.5), c, sections=12, minor_sections=6, rot=rot_x(np.pi / 2))
    return b.finish("mug")


@family("bottle", ("obj",), weight=1.5)
def bottle(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.025, 0.05), u(rng, 0.18, 0.35)
    neck = r * u(rng, 0.3, 0.5)
    shoulder = h * u(rng, 0.5, 0.75)
    c = choice(rng, ((60, 110, 60), (110, 70, 30), (200, 220, 225), (40, 40,
            45))) if rng.random() < 0.6 else plastic(rng)
    prof = [(r, 0.0), (r, shoulder), (r * 0.8, shoulder + (h - shoulder) * 0.3), (neck, h * 0.88), (neck, h - 0.02)]
    b.lathe([(0.0, 0.0)] + prof + [(0.0, h - 0.02)], as_rgb(c), sections=16)
    b.cylinder(neck * 1.15, 0.025, (0, 0, h - 0.025), any_color(rng), sections=12)
    if rng.random() < 0.6:  # label
        b.cylinder(r * 1.01, shoulder * 0.5, (0, 0, shoulder * 0.3), any_color(rng), sections=16)
    return b.finish(choice(rng, ("bottle", "bottle", "water bottle", "wine bottle")) if h > 0.28 else "bottle")



@family("bowl", ("obj",))
def bowl(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.06, 0.15), u(rng, 0.04, 0.09)
    c = ceramic(rng) if rng.random() < 0.7 else wood(rng)
    foot = r * u(rng, 0.35, 0.55)
    ts = np.linspace(0, 1, 6)
    outer = [(foot + (r - foot) * np.sin(t * np.pi / 2), h * (1 - np.cos(t * np.pi / 2))) for t in ts]
    outer[0] = (foot, 0.0)
    _vessel(b, rng, outer, 0.005, c, sections=24)
    return b.finish("bowl")


@family("plate", ("obj",), weight=0.6)
def plate(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r = u(rng, 0.08, 0.15)
    c = ceramic(rng)
    n = int(rng.integers(1, 5))
    for k in range(n):
        b.lathe([(r * 0.6, k * 0.018), (r, k * 0.018 + 0.015), (r - 0.01, k * 0.018 + 0.018), (r * 0.6,
                k * 0.018 + 0.006),
                 (0, k * 0.018 + 0.006)], c, sections=24)
    return b.finish("plate", extra={"stacked": n})


@family("vase", ("obj",), weight=1.2)
def vase(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    h = u(rng, 0.15, 0.5)
    n = int(rng.integers(4, 8))
    zs = np.linspace(0, h, n)
    base_r = u(rng, 0.03, 0.1)
    rs = base_r * np.exp(np.cumsum(rng.normal(0, 0.25, n)))
    rs = np.clip(rs, 0.02, 0.18)
    rs[-1] = max(0.02, min(rs[-1], rs[-2]))
    c = ceramic(rng) if rng.random() < 0.7 else GLASS
    _vessel(b, rng, list(zip(rs.tolist(), zs.tolist())), 0.006, c, sections=20)
    if rng.random() < 0.4:  # flowers
        for _ in range(int(rng.integers(2, 6))):
            top = (rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05), h + rng.uniform(0.1, 0.25))
            b.bar((0, 0, h * 0.5), top, 0.003, leaf(rng), sections=5)
            b.ellipsoid((0.025, 0.025, 0.02), top, any_color(rng))
    return b.finish("vase")


@family("cooking_pot", ("obj",), weight=0.7)
def cooking_pot(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.08, 0.15), u(rng, 0.08, 0.2)
    c = metal(rng)
    _vessel(b, rng, [(r, 0.0), (r, h)], 0.004, c)
    for sx in (-1, 1):
        b.slab(sx * r - (0 if sx > 0 else 0.04), sx * r + (0.04 if sx > 0 else 0), -0.015, 0.015, h - 0.03,
                h - 0.015, DARK)
    if rng.random() < 0.6:
        b.cylinder(r + 0.005, 0.008, (0, 0, h), c, sections=24, top_radius=r * 0.9)
        b.ellipsoid((0.02, 0.02, 0.015), (0, 0, h + 0.012), DARK)
    return b.finish("pot")


@family("frying_pan", ("obj",), weight=0.5)
def frying_pan(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r = u(rng, 0.1, 0.16)
    c = choice(rng, (DARK, (60, 60, 62), (170, 170, 175)))
    _vessel(b, rng, [(r * 0.85, 0.0), (r, 0.045)], 0.004, c)
    L = u(rng, 0.15, 0.22)
    b.beam((r * 0.95, 0, 0.035), (r + L, 0, 0.05), 0.025, 0.012, DARK)
    return b.finish("pan")


@family("kettle", ("obj",), weight=0.5)
def kettle(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.07, 0.1), u(rng, 0.15, 0.25)
    c = metal(rng) if rng.random() < 0.5 else plastic(rng)
    b.lathe([(r, 0.0), (r, h * 0.6), (r * 0.6, h), (0, h)], c, sections=20)
    b.cylinder(r * 1.05, 0.02, (0, 0, 0), DARK, sections=20)
    b.bar((-r * 0.9, 0, h * 0.5), (-r * 1.6, 0, h * 0.8), 0.012, c)
    b.bar((r * 0.2, 0, h * 0.95), (-r * 0.9, 0, h * 0.95), 0.012, DARK)
    b.bar((-r * 0.9, 0, h * 0.95), (-r * 0.9, 0, h * 0.55), 0.012, DARK)
    return b.finish("kettle")


@family("can", ("obj",), weight=0.6)
def can(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.03, 0.05), u(rng, 0.1, 0.16)
    b.cylinder(r * 0.92, 0.005, (0, 0, 0), (190, 190, 195), sections=16)
    b.cylinder(r, h - 0.01, (0, 0, 0.005), any_color(rng), sections=16)
    b.cylinder(r * 0.92, 0.005, (0, 0, h - 0.005), (190, 190, 195), sections=16)
    return b.finish(choice(rng, ("can", "soda can", "jar")) if r > 0.04 else "can")


@family("tray", ("obj",), weight=0.5)
def tray(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d = u(rng, 0.25, 0.5), u(rng, 0.2, 0.35)
    c = material(rng) if rng.random() < 0.6 else plastic(rng)
    h, t = u(rng, 0.02, 0.05), 0.008
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, t, c)
    b.slab(-w / 2, w / 2, -d / 2, -d / 2 + t, t, h, c)
    b.slab(-w / 2, w / 2, d / 2 - t, d / 2, t, h, c)
    b.slab(-w / 2, -w / 2 + t, -d / 2 + t, d / 2 - t, t, h, c)
    b.slab(w / 2 - t, w / 2, -d / 2 + t, d / 2 - t, t, h, c)
    return b.finish("tray", supports=[rect_support(-w / 2 + t, w / 2 - t, -d / 2 + t, d / 2 - t, t, inset=0.01)])


@family("basket", ("obj",), weight=0.6)
def basket(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    c = choice(rng, ((190, 150, 100), (160, 120, 80), (120, 90, 60))) if rng.random() < 0.7 else plastic(rng)
    w, d, h = u(rng, 0.2, 0.45), u(rng, 0.15, 0.35), u(rng, 0.1, 0.25)
    t = 0.01
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, t, c)
    for y0, y1 in ((-d / 2, -d / 2 + t), (d / 2 - t, d / 2)):
        b.slab(-w / 2, w / 2, y0, y1, t, h, c)
    for x0, x1 in ((-w / 2, -w / 2 + t), (w / 2 - t, w / 2)):
        b.slab(x0, x1, -d / 2 + t, d / 2 - t, t, h, c)
    if rng.random() < 0.5:  # handle arch
        b.torus(w / 2 - t, 0.007, (0, 0, h), c, sections=16, minor_sections=6,
                rot=rot_x(np.pi / 2) @ np.diag([1.0, h * 1.5 / (w / 2), 1.0]))
    return b.finish("basket")


@family("candle", ("obj",), weight=0.4)
def candle(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.015, 0.04), u(rng, 0.05, 0.25)
    if rng.random() < 0.5:
        b.cylinder(r * 2, 0.02, (0, 0, 0), metal(rng), sections=16, top_radius=r * 1.2)
    b.cylinder(r, h, (0, 0, 0.02), (240, 235, 215) if rng.random() < 0.6 else any_color(rng), sections=16)
    b.cylinder(0.002, 0.012, (0, 0, h + 0.02), DARK, sections=5)
    return b.finish("candle")


@family("tissue_box", ("obj",), weight=0.4)
def tissue_box(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.12, 0.25), u(rng, 0.11, 0.13), u(rng, 0.06, 0.13)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, any_color(rng))
    b.ellipsoid((0.04, 0.03, 0.03), (0, 0, h), WHITE)
    return b.finish("tissue box")


@family("box", ("obj",), weight=1.5)
def box(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.1, 0.6), u(rng, 0.1, 0.45), u(rng, 0.05, 0.45)
    cardboard = rng.random() < 0.5
    c = (190, 150, 105) if cardboard else any_color(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, c)
    if cardboard:
        b.slab(-0.03, 0.03, -d / 2 - 0.001, d / 2 + 0.001, 0, h + 0.001, (200, 180, 140))
    elif rng.random() < 0.5:  # lid
        b.slab(-w / 2 - 0.005, w / 2 + 0.005, -d / 2 - 0.005, d / 2 + 0.005, h - min(0.04, h / 3), h + 0.003,
               as_rgb(np.clip(np.array(c) * 0.8, 0, 255)))
        h = h + 0.003
    sup = []
    if w > 0.15 and d > 0.15 and not cardboard:
        sup = [rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.02)]
    elif cardboard and w / 2 - 0.03 > 0.06 and d > 0.1:  # beside the tape strip
        sup = [rect_support(0.03, w / 2, -d / 2, d / 2, h, inset=0.02)]
    return b.finish("box", supports=sup)


@family("book", ("obj",), weight=1.0)
def book(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, t = u(rng, 0.12, 0.25), u(rng, 0.15, 0.32), u(rng, 0.01, 0.06)
    cover = any_color(rng)
    if rng.random() < 0.5:  # lying flat, spine toward -y... pages inset on three sides
        b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, 0.003, cover)
        b.slab(-w / 2, w / 2, -d / 2, d / 2, t - 0.003, t, cover)
        b.slab(-w / 2, -w / 2 + 0.003, -d / 2, d / 2, 0.003, t - 0.003, cover)
        b.slab(-w / 2 + 0.003, w / 2 - 0.004, -d / 2 + 0.004, d / 2 - 0.004, 0.003, t - 0.003, (240, 235, 220))
        return b.finish("book")
    # standing upright, spine facing -y
    b.slab(-t / 2, t / 2, -w / 2, -w / 2 + 0.003, 0, d, cover)
    b.slab(-t / 2, -t / 2 + 0.003, -w / 2, w / 2, 0, d, cover)
    b.slab(t / 2 - 0.003, t / 2, -w / 2, w / 2, 0, d, cover)
    b.slab(-t / 2 + 0.003, t / 2 - 0.003, -w / 2 + 0.003, w / 2 - 0.004, 0.004, d - 0.004, (240, 235, 220))
    return b.finish("book")


@family("book_stack", ("obj",), weight=1.0)
def book_stack(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    n = int(rng.integers(2, 8))
    upright = rng.random() < 0.5
    pos = 0.0
    for _ in range(n):
        w, d, t = u(rng, 0.13, 0.24), u(rng, 0.17, 0.3), u(rng, 0.012, 0.05)
        a = rng.normal(0, 0.08)
        c = any_color(rng)
        if upright:  # a row of books standing side by side along x
            b.box((t, w, d), (pos + t / 2, 0, d / 2), c)
            b.box((t - 0.004, w - 0.006, d - 0.008), (pos + t / 2, -0.0031, d / 2), (240, 235, 220))
        else:
            b.box((w, d, t), (rng.normal(0, 0.01), rng.normal(0, 0.01), pos + t / 2), c, rot=rot_z(a))
        pos += t
    return b.finish("books")


@family("table_lamp", ("obj",), weight=1.2)
def table_lamp(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    base, shade = (ceramic(rng) if rng.random() < 0.5 else metal(rng)), (fabric(rng) if rng.random() < 0.7
                                                                         else (245, 240, 225))
    h = u(rng, 0.3, 0.65)
    if rng.random() < 0.6:
        br = u(rng, 0.05, 0.1)
        b.lathe([(br * 0.7, 0.0), (br, h * 0.2), (br * u(rng, 0.3, 1.0), h * 0.45), (0.012, h * 0.55)], base,
                sections=20)
        b.cylinder(0.008, h * 0.3, (0, 0, h * 0.55), metal(rng), sections=8)
        sr = u(rng, 0.1, 0.2)
        b.cylinder(sr, h * 0.35, (0, 0, h * 0.65), shade, sections=20, top_radius=sr * u(rng, 0.5, 0.9))
    else:  # desk lamp: a bent arm and a small head
        c = metal(rng) if rng.random() < 0.5 else plastic(rng)
        b.cylinder(0.07, 0.02, (0, 0, 0), c, sections=16)
        reach = u(rng, 0.1, 0.25)
        b.bar((0, 0, 0.02), (0, 0.05, h * 0.6), 0.008, c)
        b.bar((0, 0.05, h * 0.6), (0, -reach, h), 0.008, c)
        b.cylinder(0.05, 0.08, (0, -reach, h - 0.08), c, sections=16, top_radius=0.02)
    return b.finish("lamp")


@family("plant_small", ("obj",), weight=1.2)
def plant_small(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, ph = u(rng, 0.04, 0.1), u(rng, 0.05, 0.14)
    flower_pot(b, rng, r, ph, ceramic(rng) if rng.random() < 0.7 else plastic(rng))
    foliage(b, rng, r, ph, u(rng, 0.08, 0.4))
    return b.finish("plant")


@family("photo_frame", ("obj",), weight=0.6)
def photo_frame(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.1, 0.25), u(rng, 0.1, 0.25)
    c = material(rng)
    tilt = rot_x(-u(rng, 0.1, 0.25))
    b.box((w, 0.015, h), (0, 0, h / 2), c, rot=tilt)
    b.box((w - 0.02, 0.004, h - 0.02), tilt @ np.array([0, -0.008, 0]) + np.array([0, 0, h / 2]),
            any_color(rng), rot=tilt)
    b.beam((0, 0.0, h * 0.5), (0, h * 0.35, 0.0), 0.02, 0.006, c)
    return b.finish("picture")


@family("pillow", ("obj",), weight=0.8)
def pillow(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, t = u(rng, 0.3, 0.6), u(rng, 0.3, 0.5), u(rng, 0.08, 0.16)
    b.ellipsoid((w / 2, d / 2, t / 2), (0, 0, t / 2), fabric(rng), subdivisions=2)
    return b.finish("pillow")


@family("fruit", ("obj",), weight=0.8)
def fruit(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    kind = choice(rng, ("apple", "orange", "banana", "pear", "fruit bowl"))
    if kind in ("apple", "orange"):
        r = u(rng, 0.035, 0.05)
        col = choice(rng, ((190, 30, 30), (120, 180, 60), (230, 200, 60))) if kind == "apple" else (240, 140, 30)
        b.ellipsoid((r, r, r * 0.92), (0, 0, r * 0.92), as_rgb(col), subdivisions=2)
        b.cylinder(0.003, 0.015, (0, 0, r * 1.8), (90, 60, 30), sections=5)
    elif kind == "pear":
        b.lathe([(0.035, 0.005), (0.04, 0.03), (0.02, 0.08), (0.012, 0.1)], (190, 200, 80), sections=16)
    elif kind == "banana":
        radius = u(rng, 0.09, 0.13)
        arc = np.linspace(-0.9, 0.9, 6)
        for k in range(int(rng.integers(1, 5))):
            pts = [(radius * np.sin(a), radius * (1 - np.cos(a)) + k * 0.03, 0.018 + 0.004 * k) for a in arc]
            for p0, p1 in zip(pts[:-1], pts[1:]):
                b.bar(p0, p1, 0.017, (235, 210, 70), sections=8)
            b.ellipsoid((0.017, 0.017, 0.017), pts[0], (235, 210, 70))
            b.ellipsoid((0.017, 0.017, 0.017), pts[-1], (120, 100, 40))
    else:
        r = u(rng, 0.1, 0.15)
        c = ceramic(rng)
        _vessel(b, rng, [(r * 0.5, 0.0), (r, 0.06)], 0.005, c)
        for _ in range(int(rng.integers(3, 7))):
            a = rng.uniform(0, 2 * np.pi)
            rr = u(rng, 0.03, 0.045)
            d = u(rng, 0, r - rr - 0.01)
            b.ellipsoid((rr, rr, rr), (np.cos(a) * d, np.sin(a) * d, 0.04 + rr * 0.5),
                        as_rgb(choice(rng, ((190, 30, 30), (240, 140, 30), (120, 180, 60)))))
    return b.finish(kind)


@family("toaster", ("obj",), weight=0.4)
def toaster(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.25, 0.35), u(rng, 0.15, 0.22), u(rng, 0.18, 0.22)
    c = metal(rng) if rng.random() < 0.6 else plastic(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0.01, h, c)
    b.slab(-w / 2 + 0.01, w / 2 - 0.01, -d / 2 + 0.01, d / 2 - 0.01, 0, 0.01, DARK)
    for k in (-1, 1):
        b.slab(-w / 2 + 0.04, w / 2 - 0.04, k * 0.035 - 0.012, k * 0.035 + 0.012, h - 0.001, h + 0.002, DARK)
    b.slab(w / 2, w / 2 + 0.02, -0.01, 0.01, h * 0.6, h * 0.7, DARK)
    return b.finish("toaster")


@family("microwave", ("obj",), weight=0.6)
def microwave(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.45, 0.6), u(rng, 0.32, 0.42), u(rng, 0.26, 0.34)
    c = WHITE if rng.random() < 0.4 else metal(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0.01, h, c)
    for sx in (-1, 1):
        for sy in (-1, 1):
            b.cylinder(0.012, 0.012, (sx * (w / 2 - 0.04), sy * (d / 2 - 0.04), 0), DARK, sections=8)
    b.slab(-w / 2 + 0.02, w / 2 - 0.15, -d / 2 - 0.005, -d / 2, 0.04, h - 0.04, DARK)
    b.slab(w / 2 - 0.13, w / 2 - 0.03, -d / 2 - 0.005, -d / 2, h * 0.5, h - 0.04, (60, 60, 65))
    return b.finish("microwave", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.03)])


@family("jar", ("obj",), weight=0.5)
def jar(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.03, 0.07), u(rng, 0.06, 0.2)
    b.lathe([(r, 0.0), (r, h * 0.85), (r * 0.85, h * 0.9), (r * 0.85, h)], GLASS, sections=20)
    b.cylinder(r * 0.9, 0.02, (0, 0, h), any_color(rng), sections=20)
    b.cylinder(r * 0.95, h * 0.6, (0, 0, 0.005), any_color(rng), sections=20)
    return b.finish("jar")


@family("paper_stack", ("obj",), weight=0.4)
def paper_stack(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d = choice(rng, ((0.21, 0.297), (0.297, 0.21), (0.216, 0.279)))
    t = u(rng, 0.005, 0.05)
    b.box((w, d, t), (0, 0, t / 2), (245, 245, 240), rot=rot_z(rng.normal(0, 0.05)))
    if rng.random() < 0.5:
        b.box((w * 0.95, d * 0.95, 0.002), (0.01, 0.005, t + 0.001), (250, 250, 246), rot=rot_z(rng.normal(0, 0.2)))
    return b.finish("paper")


@family("clock_alarm", ("obj",), weight=0.4)
def clock_alarm(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    c = plastic(rng)
    if rng.random() < 0.5:
        r = u(rng, 0.04, 0.07)
        b.cylinder(r, 0.04, (0, 0.02, r + 0.01), c, sections=20, rot=rot_x(np.pi / 2))
        b.cylinder(r * 0.85, 0.045, (0, 0.022, r + 0.01), WHITE, sections=20, rot=rot_x(np.pi / 2))
        for sx in (-1, 1):
            b.bar((sx * r * 0.5, 0, 0), (sx * r * 0.6, 0, 0.02), 0.004, c)
            b.ellipsoid((r * 0.35, r * 0.25, r * 0.25), (sx * r * 0.6, 0, 2 * r + 0.01), metal(rng))
    else:
        w, d, h = u(rng, 0.1, 0.18), u(rng, 0.05, 0.08), u(rng, 0.05, 0.09)
        b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, c)
        b.slab(-w / 2 + 0.01, w / 2 - 0.01, -d / 2 - 0.002, -d / 2, 0.01, h - 0.01, (30, 40, 30))
    return b.finish("alarm clock")


@family("shoe", ("obj", "floor"), weight=0.5)
def shoe(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    L, w = u(rng, 0.22, 0.32), u(rng, 0.08, 0.11)
    c = any_color(rng) if rng.random() < 0.5 else DARK
    pair = rng.random() < 0.7
    for sx in ((-0.6, 0.6) if pair else (0.0,)):
        x = sx * w * 1.1
        b.slab(x - w / 2, x + w / 2, -L / 2, L / 2, 0, 0.02, (235, 235, 235) if rng.random() < 0.5 else DARK)
        b.ellipsoid((w / 2 * 0.95, L / 2 * 0.95, u(rng, 0.05, 0.1)), (x, 0, 0.02), c)
        b.cylinder(w * 0.45, u(rng, 0.06, 0.12), (x, L * 0.25, 0.02), c, sections=12)
    return b.finish("shoes" if pair else "shoe")


@family("bag", ("obj", "floor"), weight=0.5)
def bag(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    kind = choice(rng, ("backpack", "bag", "suitcase"))
    c = fabric(rng)
    if kind == "suitcase":
        w, d, h = u(rng, 0.35, 0.5), u(rng, 0.2, 0.28), u(rng, 0.5, 0.75)
        b.slab(-w / 2, w / 2, -d / 2, d / 2, 0.04, h, c if rng.random() < 0.5 else plastic(rng))
        for sx in (-1, 1):
            b.cylinder(0.025, 0.02, (sx * (w / 2 - 0.05) - 0.01, d / 2 - 0.04, 0.025), DARK, sections=10,
                       rot=rot_y(np.pi / 2))
            b.slab(sx * (w / 2 - 0.05) - 0.015, sx * (w / 2 - 0.05) + 0.015, d / 2 - 0.06, d / 2 - 0.02, 0.0,
                    0.04, DARK)
        b.slab(-0.1, 0.1, -0.015, 0.015, h, h + 0.04, DARK)
    elif kind == "backpack":
        w, d, h = u(rng, 0.28, 0.36), u(rng, 0.14, 0.22), u(rng, 0.38, 0.5)
        b.slab(-w / 2, w / 2, -d / 2 + 0.05, d / 2, 0, h - w / 2 * 0.5, c)
        b.ellipsoid((w / 2, d / 2 - 0.025, w / 4), (0, 0.025, h - w / 4), c)
        b.slab(-w / 2 + 0.04, w / 2 - 0.04, -d / 2, -d / 2 + 0.05, 0.03, h * 0.45, as_rgb(np.array(c) * 0.8))
    else:
        w, d, h = u(rng, 0.3, 0.5), u(rng, 0.12, 0.2), u(rng, 0.2, 0.35)
        b.cylinder(w / 2, h, (0, 0, 0), c, sections=16, radius_y=d / 2, top_radius=w / 2 * 0.85)
        b.torus(w * 0.3, 0.01, (0, 0, h), DARK, sections=16, minor_sections=6, rot=rot_x(np.pi / 2))
    return b.finish(kind)
