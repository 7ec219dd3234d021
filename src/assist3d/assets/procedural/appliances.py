"""Appliances, bathroom fixtures, pianos, plants, lamps, bins and other floor items."""

from __future__ import annotations

import manifold3d as mf
import numpy as np

from ._build import (DARK, GLASS, WHITE, MeshBuilder, Shape, ceramic, fabric, material, metal, paint, plastic,
                     rect_support, rot_x, wood)
from ._parts import choice, doors, flower_pot, foliage, handle, u
from ._registry import family


def _white_goods(rng: np.random.Generator):
    return WHITE if rng.random() < 0.6 else metal(rng)


@family("refrigerator", ("floor",))
def refrigerator(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.55, 0.9), u(rng, 0.6, 0.75), u(rng, 1.4, 2.0)
    body, hc = _white_goods(rng), metal(rng)
    b.slab(-w / 2, w / 2, -d / 2 + 0.04, d / 2, 0.02, h, body)
    b.slab(-w / 2 + 0.03, w / 2 - 0.03, -d / 2 + 0.06, d / 2 - 0.05, 0, 0.02, DARK)
    split = h * u(rng, 0.3, 0.7)
    if w > 0.8 and rng.random() < 0.5:  # side-by-side doors
        for sx in (-1, 1):
            x0, x1 = (-w / 2, -0.003) if sx < 0 else (0.003, w / 2)
            b.slab(x0, x1, -d / 2, -d / 2 + 0.04, 0.03, h, body)
            handle(b, rng, -sx * 0.04, -d / 2, h * 0.6, hc, vertical=True, length=0.5)
    else:
        for z0, z1 in ((0.03, split - 0.003), (split + 0.003, h)):
            b.slab(-w / 2, w / 2, -d / 2, -d / 2 + 0.04, z0, z1, body)
            handle(b, rng, w / 2 - 0.06, -d / 2, (z0 + z1) / 2, hc, vertical=True, length=min(0.4, (z1 - z0) * 0.5))
    return b.finish("refrigerator", supports=[rect_support(-w / 2, w / 2, -d / 2 + 0.04, d / 2, h, inset=0.03)])


@family("washing_machine", ("floor",))
def washing_machine(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.58, 0.62), u(rng, 0.5, 0.65), u(rng, 0.82, 0.88)
    body = _white_goods(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, body)
    b.slab(-w / 2 + 0.02, w / 2 - 0.02, -d / 2 - 0.005, -d / 2, h - 0.12, h - 0.02, (200, 200, 205))
    r = u(rng, 0.17, 0.22)
    zc = h * u(rng, 0.42, 0.5)
    if rng.random() < 0.8:  # front loader: porthole door
        b.torus(r, 0.03, (0, -d / 2 - 0.02, zc), (190, 190, 195), sections=24, rot=rot_x(np.pi / 2))
        b.cylinder(r - 0.01, 0.03, (0, -d / 2 + 0.005, zc), GLASS, sections=24, rot=rot_x(np.pi / 2))
    for k in range(int(rng.integers(1, 4))):
        b.cylinder(0.025, 0.02, (w / 2 - 0.08 - k * 0.08, -d / 2, h - 0.07), (120, 120, 125), sections=12,
                   rot=rot_x(np.pi / 2))
    cls = choice(rng, ("washing machine", "dryer")) if rng.random() < 0.3 else "washing machine"
    return b.finish(cls, supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.03)])


@family("dishwasher", ("floor",), weight=0.5)
def dishwasher(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.45, 0.6), u(rng, 0.55, 0.62), u(rng, 0.82, 0.87)
    body = _white_goods(rng)
    b.slab(-w / 2, w / 2, -d / 2 + 0.03, d / 2, 0, h, body)
    b.slab(-w / 2, w / 2, -d / 2, -d / 2 + 0.03, 0.1, h, body)
    b.slab(-w / 2 + 0.02, w / 2 - 0.02, -d / 2 - 0.002, -d / 2 + 0.03, h - 0.1, h - 0.02, DARK)
    handle(b, rng, 0, -d / 2, h - 0.14, metal(rng), length=w * 0.6)
    return b.finish("dishwasher", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.03)])


@family("stove", ("floor",), weight=0.7)
def stove(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.5, 0.9), u(rng, 0.55, 0.65), u(rng, 0.85, 0.92)
    body = _white_goods(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, body)
    b.slab(-w / 2 + 0.04, w / 2 - 0.04, -d / 2 - 0.02, -d / 2, 0.12, h - 0.15, DARK)
    handle(b, rng, 0, -d / 2 - 0.02, h - 0.18, metal(rng), length=w * 0.7)
    nb = 4 if w > 0.55 else 2
    for k in range(nb):
        x = (-0.25 + 0.5 * (k % 2)) * w
        y = (-0.2 + 0.4 * (k // 2)) * d if nb == 4 else 0.0
        b.cylinder(u(rng, 0.07, 0.11), 0.015, (x, y, h), DARK, sections=16)
    b.slab(-w / 2, w / 2, d / 2 - 0.04, d / 2, h, h + u(rng, 0.05, 0.15), body)
    for k in range(4):
        b.cylinder(0.018, 0.02, ((-0.3 + 0.2 * k) * w, -d / 2, h - 0.07), DARK, sections=10, rot=rot_x(np.pi / 2))
    return b.finish("stove")


@family("toilet", ("floor",))
def toilet(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    c = ceramic(rng) if rng.random() < 0.3 else WHITE
    sh = u(rng, 0.38, 0.43)
    bw, bd = u(rng, 0.17, 0.2), u(rng, 0.22, 0.26)
    b.cylinder(bw * 0.65, sh * 0.6, (0, 0, 0), c, sections=20, radius_y=bd * 0.65, top_radius=bw * 0.85)
    b.cylinder(bw * 0.9, sh * 0.45, (0, 0, sh * 0.5), c, sections=24, radius_y=bd * 0.95, top_radius=bw)
    seat = (245, 245, 245) if rng.random() < 0.7 else DARK
    b.torus(1.0, 0.2, (0, 0, sh - 0.01), seat, sections=24, minor_sections=6, rot=np.diag([bw * 0.82, bd * 0.82, 0.1]))
    tw, td, th = u(rng, 0.36, 0.46), u(rng, 0.14, 0.2), u(rng, 0.3, 0.42)
    yt = bd * 0.85
    b.slab(-tw / 2, tw / 2, yt, yt + td, sh - 0.05, sh - 0.05 + th, c)
    b.slab(-tw / 2 - 0.01, tw / 2 + 0.01, yt - 0.01, yt + td + 0.01, sh - 0.05 + th, sh - 0.03 + th, c)
    b.slab(0.05, 0.1, yt - 0.012, yt, sh + th - 0.12, sh + th - 0.1, metal(rng))
    return b.finish("toilet")


@family("bathtub", ("floor",), weight=0.6)
def bathtub(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 1.5, 1.8), u(rng, 0.7, 0.85), u(rng, 0.5, 0.6)
    t = u(rng, 0.05, 0.1)
    outer = mf.Manifold.cube((w, d, h), True).translate((0, 0, h / 2))
    inner = mf.Manifold.cube((w - 2 * t, d - 2 * t, h), True).translate((0, 0, h / 2 + u(rng, 0.08, 0.15)))
    if rng.random() < 0.5:  # rounded basin
        basin = mf.Manifold.cylinder(h, 1.0, 1.0, 32).scale(((w - 2 * t) / 2, (d - 2 * t) / 2, 1.0))
        inner = basin.translate((0, 0, u(rng, 0.08, 0.15)))
    b.manifold(outer - inner, ceramic(rng) if rng.random() < 0.3 else WHITE)
    tap = metal(rng)
    b.bar((-w / 2 + t / 2, 0, h), (-w / 2 + t / 2, 0, h + 0.12), 0.015, tap)
    b.bar((-w / 2 + t / 2, 0, h + 0.12), (-w / 2 + t / 2 + 0.12, 0, h + 0.12), 0.012, tap)
    return b.finish("bathtub")


@family("sink_vanity", ("floor",))
def sink_vanity(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.5, 1.2), u(rng, 0.42, 0.55), u(rng, 0.8, 0.9)
    body, top = material(rng), (WHITE if rng.random() < 0.6 else ceramic(rng))
    b.slab(-w / 2, w / 2, -d / 2 + 0.02, d / 2, u(rng, 0.0, 0.15), h - 0.03, body)
    doors(b, rng, -w / 2 + 0.01, w / 2 - 0.01, 0.16, h - 0.05, -d / 2 + 0.02, 1 if w < 0.7 else 2, body)
    rx, ry = min(0.25, w / 2 - 0.08) * u(rng, 0.7, 1.0), (d / 2 - 0.08) * u(rng, 0.75, 1.0)
    slab = mf.Manifold.cube((w, d, 0.04), True).translate((0, 0, h - 0.01))
    bowl = mf.Manifold.sphere(1.0, 24).scale((rx, ry, 0.14)).translate((0, -0.02, h + 0.01))
    b.manifold(slab - bowl, top)
    tap = metal(rng)
    yb = -0.02 + ry + 0.03
    b.bar((0, yb, h + 0.01), (0, yb, h + 0.16), 0.013, tap)
    b.bar((0, yb, h + 0.16), (0, yb - 0.1, h + 0.14), 0.01, tap)
    return b.finish("sink")


@family("piano", ("floor",), weight=0.5)
def piano(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 1.4, 1.55), u(rng, 0.5, 0.62), u(rng, 1.0, 1.3)
    body = choice(rng, ((20, 20, 22), (70, 40, 25), (110, 70, 40), (240, 240, 240)))
    kd = 0.25
    b.slab(-w / 2, w / 2, -d / 2 + kd, d / 2, 0, h, body)
    b.slab(-w / 2, w / 2, -d / 2, -d / 2 + kd, 0.6, 0.68, body)
    b.slab(-w / 2 + 0.06, w / 2 - 0.06, -d / 2 + 0.02, -d / 2 + kd - 0.05, 0.68, 0.7, WHITE)
    for k in range(12):
        x = -w / 2 + 0.12 + k * (w - 0.24) / 11
        b.slab(x - 0.02, x + 0.02, -d / 2 + 0.1, -d / 2 + kd - 0.05, 0.7, 0.715, DARK)
    for sx in (-1, 1):
        b.slab(sx * (w / 2 - 0.03) - 0.03, sx * (w / 2 - 0.03) + 0.03, -d / 2, -d / 2 + kd, 0, 0.75, body)
        b.slab(sx * (w / 2 - 0.03) - 0.03, sx * (w / 2 - 0.03) + 0.03, -d / 2 + 0.02, -d / 2 + 0.08, 0, 0.6, body)
    return b.finish("piano", supports=[rect_support(-w / 2, w / 2, -d / 2 + kd, d / 2, h, inset=0.03)])


@family("plant_floor", ("floor",))
def plant_floor(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, ph = u(rng, 0.12, 0.25), u(rng, 0.2, 0.45)
    flower_pot(b, rng, r, ph, ceramic(rng))
    foliage(b, rng, r, ph, u(rng, 0.5, 1.4))
    return b.finish("plant")


@family("floor_lamp", ("floor",))
def floor_lamp(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    h = u(rng, 1.4, 1.85)
    frame, shade = metal(rng), (fabric(rng) if rng.random() < 0.7 else plastic(rng))
    br = u(rng, 0.12, 0.2)
    b.cylinder(br, 0.03, (0, 0, 0), frame, sections=20, top_radius=br * 0.8)
    sr, sh = u(rng, 0.15, 0.25), u(rng, 0.2, 0.35)
    if rng.random() < 0.6:
        b.cylinder(0.012, h - sh * 0.5, (0, 0, 0.03), frame, sections=8)
        b.cylinder(sr, sh, (0, 0, h - sh), shade, sections=20, top_radius=sr * u(rng, 0.55, 0.9))
    else:  # arc lamp: a bent arm and a dome hanging forward
        reach = u(rng, 0.3, 0.6)
        b.bar((0, 0, 0.03), (0, 0, h * 0.8), 0.012, frame)
        b.bar((0, 0, h * 0.8), (0, -reach, h), 0.012, frame)
        b.cylinder(sr * 0.3, sh * 0.8, (0, -reach, h - sh * 0.8), shade, sections=20, top_radius=sr * 0.7,
                   rot=rot_x(np.pi))
    return b.finish("lamp")


@family("trash_can", ("floor",))
def trash_can(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    h = u(rng, 0.3, 0.75)
    c = plastic(rng) if rng.random() < 0.5 else metal(rng)
    if rng.random() < 0.6:
        r = u(rng, 0.12, 0.22)
        rb = r * u(rng, 0.75, 1.0)
        t = 0.008
        b.lathe([(rb, 0), (r, h), (r - t, h), (rb - t, t), (0, t)], c, sections=24)
        if rng.random() < 0.4:
            b.cylinder(r + 0.005, 0.03, (0, 0, h), c, sections=24, top_radius=r * 0.9)
    else:
        w, d = u(rng, 0.25, 0.4), u(rng, 0.2, 0.35)
        b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, c)
        b.slab(-w / 2 - 0.005, w / 2 + 0.005, -d / 2 - 0.005, d / 2 + 0.005, h, h + 0.03, DARK)
    return b.finish("trash can")


@family("standing_fan", ("floor",), weight=0.5)
def standing_fan(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    h = u(rng, 1.0, 1.4)
    c = plastic(rng) if rng.random() < 0.6 else metal(rng)
    b.cylinder(u(rng, 0.15, 0.22), 0.04, (0, 0, 0), c, sections=20)
    b.cylinder(0.015, h - 0.1, (0, 0, 0.04), c, sections=8)
    r = u(rng, 0.18, 0.25)
    b.ellipsoid((0.07, 0.1, 0.07), (0, 0.05, h), c)
    b.torus(r, 0.008, (0, -0.08, h), c, sections=24, minor_sections=6, rot=rot_x(np.pi / 2))
    for k in range(int(rng.integers(3, 6))):
        a = 2 * np.pi * k / 5
        b.ellipsoid((r * 0.4, 0.008, 0.06), (np.cos(a) * r * 0.45, -0.06, h + np.sin(a) * r * 0.45), (200, 200, 205),
                    rot=np.array([[np.cos(a), 0, -np.sin(a)], [0, 1, 0], [np.sin(a), 0, np.cos(a)]]))
    return b.finish("fan")


@family("coat_stand", ("floor",), weight=0.5)
def coat_stand(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    h = u(rng, 1.6, 1.9)
    c = wood(rng) if rng.random() < 0.6 else metal(rng)
    b.cylinder(0.02, h, (0, 0, 0), c, sections=10)
    for k in range(int(rng.integers(3, 5))):
        a = 2 * np.pi * k / 4 + 0.4
        b.bar((0, 0, 0.3), (np.cos(a) * 0.25, np.sin(a) * 0.25, 0.0), 0.015, c)
        b.bar((0, 0, h - 0.15), (np.cos(a) * 0.15, np.sin(a) * 0.15, h - 0.02), 0.01, c)
    b.ellipsoid((0.03, 0.03, 0.03), (0, 0, h), c)
    return b.finish("coat rack")


@family("laundry_basket", ("floor", "obj"), weight=0.4)
def laundry_basket(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.18, 0.28), u(rng, 0.3, 0.55)
    c = plastic(rng) if rng.random() < 0.5 else (190, 160, 110)
    t = 0.01
    b.lathe([(r * 0.85, 0), (r, h), (r - t, h), (r * 0.85 - t, t), (0, t)], c, sections=20)
    if rng.random() < 0.5:
        b.ellipsoid((r * 0.8, r * 0.8, 0.06), (0, 0, h - 0.03), fabric(rng))
    return b.finish("laundry basket")


@family("floor_heater", ("floor",), weight=0.3)
def floor_heater(rng: np.random.Generator) -> Shape:
    """A free-standing oil heater: fins on small feet."""
    b = MeshBuilder()
    n = int(rng.integers(5, 12))
    h, d = u(rng, 0.5, 0.65), u(rng, 0.12, 0.16)
    c = WHITE if rng.random() < 0.7 else paint(rng)
    pitch = 0.05
    for k in range(n):
        x = (k - (n - 1) / 2) * pitch
        b.slab(x - 0.015, x + 0.015, -d / 2, d / 2, 0.06, h, c)
    w = n * pitch
    b.slab(-w / 2, w / 2, -0.02, 0.02, 0.08, h - 0.05, c)
    for sx in (-1, 1):
        b.slab(sx * w / 3 - 0.015, sx * w / 3 + 0.015, -d / 2 - 0.05, d / 2 + 0.05, 0, 0.06, DARK)
    return b.finish("heater")
