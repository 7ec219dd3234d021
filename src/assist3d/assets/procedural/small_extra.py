"""More small objects: glasses, teapots, kitchen appliances, buckets, sports gear, office items."""

from __future__ import annotations

import numpy as np

from ._build import (DARK, GLASS, WHITE, MeshBuilder, Shape, any_color, ceramic, metal, plastic, rect_support, rot_x,
                     rot_y, wood)
from ._parts import choice, u
from ._registry import family
from .small_home import _vessel


@family("wine_glass", ("obj",), weight=0.5)
def wine_glass(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.03, 0.045), u(rng, 0.14, 0.22)
    stem = h * u(rng, 0.35, 0.5)
    base = r * u(rng, 0.8, 1.1)
    b.lathe([(base, 0.0), (base, 0.004), (0.005, 0.01), (0.004, stem), (r * 0.9, stem + (h - stem) * 0.4),
             (r, h), (r - 0.002, h), (0.0, stem + 0.01)], GLASS, sections=20)
    return b.finish("glass")


@family("teapot", ("obj",), weight=0.4)
def teapot(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.07, 0.1), u(rng, 0.1, 0.15)
    c = ceramic(rng)
    b.lathe([(r * 0.7, 0.0), (r, h * 0.4), (r * 0.8, h * 0.85), (r * 0.35, h)], c, sections=20)
    b.cylinder(r * 0.35, 0.02, (0, 0, h), c, sections=16, top_radius=0.01)
    b.ellipsoid((0.012, 0.012, 0.012), (0, 0, h + 0.025), c)
    b.cylinder(0.013, r * 1.1, (r * 0.7, 0, h * 0.3), c, sections=10, rot=rot_y(0.9), top_radius=0.007)
    b.torus(h * 0.3, 0.009, (-r * 0.95, 0, h * 0.5), c, sections=12, minor_sections=6, rot=rot_x(np.pi / 2))
    return b.finish("teapot")


@family("coffee_maker", ("obj",), weight=0.4)
def coffee_maker(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.18, 0.28), u(rng, 0.2, 0.3), u(rng, 0.28, 0.4)
    c = DARK if rng.random() < 0.5 else metal(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, 0.04, c)
    b.slab(-w / 2, w / 2, d / 2 - d * 0.35, d / 2, 0.04, h, c)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, h - 0.07, h, c)
    pot_r = min(w, d) * 0.28
    b.lathe([(pot_r, 0.04), (pot_r, 0.04 + h * 0.35), (pot_r * 0.6, 0.04 + h * 0.45)], GLASS, base=(0, -d * 0.1, 0),
            sections=16)
    b.cylinder(pot_r * 0.95, h * 0.2, (0, -d * 0.1, 0.045), (60, 35, 20), sections=16)
    return b.finish("coffee maker")


@family("blender", ("obj",), weight=0.3)
def blender(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    s = u(rng, 0.14, 0.2)
    c = plastic(rng) if rng.random() < 0.5 else metal(rng)
    b.slab(-s / 2, s / 2, -s / 2, s / 2, 0, s * 0.7, c)
    b.cylinder(0.015, 0.012, (0, -s / 2, s * 0.35), DARK, sections=10, rot=rot_x(np.pi / 2))
    jar_h = u(rng, 0.2, 0.3)
    b.cylinder(s * 0.35, jar_h, (0, 0, s * 0.7), GLASS, sections=16, top_radius=s * 0.45)
    b.cylinder(s * 0.46, 0.025, (0, 0, s * 0.7 + jar_h), DARK, sections=16)
    return b.finish("blender")


@family("bucket", ("obj", "floor"), weight=0.4)
def bucket(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.1, 0.16), u(rng, 0.2, 0.32)
    c = plastic(rng) if rng.random() < 0.7 else metal(rng)
    _vessel(b, rng, [(r * 0.8, 0.0), (r, h)], 0.006, c, sections=20)
    b.torus(r, 0.004, (0, 0, h * 0.98), DARK, sections=16, minor_sections=4,
            rot=rot_x(np.pi / 2) @ np.diag([1.0, 0.6, 1.0]))
    return b.finish("bucket")


@family("watering_can", ("obj",), weight=0.3)
def watering_can(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.07, 0.1), u(rng, 0.15, 0.25)
    c = plastic(rng) if rng.random() < 0.6 else metal(rng)
    b.cylinder(r, h, (0, 0, 0), c, sections=16)
    b.bar((r * 0.6, 0, h * 0.2), (r * 2.6, 0, h * 1.05), 0.012, c, sections=8)
    b.cylinder(0.025, 0.02, (r * 2.6, 0, h * 1.05), c, sections=10, top_radius=0.03)
    b.torus(h * 0.35, 0.01, (-r * 0.3, 0, h), c, sections=12, minor_sections=6, rot=rot_x(np.pi / 2))
    return b.finish("watering can")


@family("dumbbell", ("obj", "floor"), weight=0.3)
def dumbbell(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    L, r = u(rng, 0.25, 0.4), u(rng, 0.05, 0.09)
    c = DARK if rng.random() < 0.6 else plastic(rng)
    along_x = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], dtype=float)
    b.cylinder(0.016, L, (-L / 2, 0, r), metal(rng), sections=10, rot=along_x)
    n = int(rng.integers(1, 4))
    for sx in (-1, 1):
        for k in range(n):
            x = sx * (L / 2 - 0.03 - k * 0.03) - 0.0125
            b.cylinder(r - k * 0.008, 0.025, (x, 0, r), c, sections=16 if rng.random() < 0.6 else 6, rot=along_x)
    return b.finish("dumbbell")


@family("trophy", ("obj",), weight=0.2)
def trophy(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    s = u(rng, 0.15, 0.35)
    gold = (212, 175, 55) if rng.random() < 0.6 else (190, 190, 195)
    b.slab(-s * 0.25, s * 0.25, -s * 0.25, s * 0.25, 0, s * 0.15, wood(rng) if rng.random() < 0.5 else DARK)
    b.cylinder(s * 0.04, s * 0.35, (0, 0, s * 0.15), gold, sections=10)
    _vessel(b, rng, [(s * 0.05, s * 0.5), (s * 0.2, s * 0.75), (s * 0.22, s)], 0.003, gold, sections=16)
    for sx in (-1, 1):
        b.torus(s * 0.08, 0.006, (sx * s * 0.22, 0, s * 0.82), gold, sections=10, minor_sections=4,
                rot=rot_x(np.pi / 2))
    return b.finish("trophy")


@family("binder", ("obj",), weight=0.4)
def binder(rng: np.random.Generator) -> Shape:
    """Ring binders and magazine files standing in a row, spines toward -y."""
    b = MeshBuilder()
    n = int(rng.integers(1, 6))
    h, d = u(rng, 0.25, 0.32), u(rng, 0.22, 0.3)
    x = 0.0
    for _ in range(n):
        t = u(rng, 0.04, 0.08)
        c = any_color(rng)
        b.slab(x, x + t, -d / 2, d / 2, 0, h, c)
        b.slab(x + t * 0.3, x + t * 0.7, -d / 2 - 0.002, -d / 2, h * 0.1, h * 0.9, (240, 240, 235))
        x += t + 0.002
    return b.finish("binder")


@family("desk_fan", ("obj",), weight=0.3)
def desk_fan(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r = u(rng, 0.1, 0.16)
    c = WHITE if rng.random() < 0.5 else plastic(rng)
    b.cylinder(r * 0.7, 0.03, (0, 0, 0), c, sections=16)
    b.slab(-0.015, 0.015, 0.0, 0.03, 0.03, r * 1.3, c)
    b.ellipsoid((0.05, 0.07, 0.05), (0, 0.05, r * 1.3 + 0.03), c)
    b.torus(r, 0.006, (0, -0.04, r * 1.3 + 0.03), c, sections=20, minor_sections=4, rot=rot_x(np.pi / 2))
    for k in range(3):
        a = 2 * np.pi * k / 3
        rot = np.array([[np.cos(a), 0, -np.sin(a)], [0, 1, 0], [np.sin(a), 0, np.cos(a)]])
        b.ellipsoid((r * 0.4, 0.006, r * 0.18), (np.cos(a) * r * 0.45, -0.03, r * 1.3 + 0.03 + np.sin(a) * r * 0.45),
                    (210, 210, 215), rot=rot)
    return b.finish("fan")


@family("toolbox", ("obj", "floor"), weight=0.3)
def toolbox(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.3, 0.55), u(rng, 0.16, 0.25), u(rng, 0.13, 0.25)
    c = choice(rng, ((200, 40, 30), (40, 70, 150), (230, 180, 30), (60, 60, 65)))
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, c)
    b.slab(-w / 2 - 0.003, w / 2 + 0.003, -d / 2 - 0.003, d / 2 + 0.003, h * 0.75, h * 0.78, DARK)
    for sx in (-1, 1):
        b.slab(sx * w * 0.2 - 0.01, sx * w * 0.2 + 0.01, -0.01, 0.01, h, h + 0.04, DARK)
    b.slab(-w * 0.2 - 0.01, w * 0.2 + 0.01, -0.012, 0.012, h + 0.04, h + 0.055, DARK)
    return b.finish("toolbox")


@family("spray_bottle", ("obj",), weight=0.3)
def spray_bottle(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.03, 0.045), u(rng, 0.15, 0.25)
    c = plastic(rng)
    b.cylinder(r, h, (0, 0, 0), c, sections=14, radius_y=r * 0.7)
    b.cylinder(r * 0.45, 0.03, (0, 0, h), WHITE, sections=10)
    b.slab(-0.012, 0.012, -0.045, 0.015, h + 0.03, h + 0.06, any_color(rng))
    b.slab(-0.006, 0.006, -0.03, -0.012, h, h + 0.03, any_color(rng))
    return b.finish(choice(rng, ("spray bottle", "soap bottle")))


@family("router", ("obj",), weight=0.3)
def router(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.15, 0.25), u(rng, 0.1, 0.16), u(rng, 0.025, 0.045)
    c = DARK if rng.random() < 0.6 else WHITE
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0.005, h, c)
    for sx in (-1, 1):
        b.slab(sx * w * 0.35 - 0.01, sx * w * 0.35 + 0.01, -d / 2 + 0.01, -d / 2 + 0.03, 0, 0.005, DARK)
        b.slab(sx * w * 0.35 - 0.01, sx * w * 0.35 + 0.01, d / 2 - 0.03, d / 2 - 0.01, 0, 0.005, DARK)
    for k in range(int(rng.integers(0, 4))):
        x = (k - 1) * w * 0.3
        b.bar((x, d / 2 - 0.01, h), (x + rng.normal(0, 0.01), d / 2 - 0.01, h + u(rng, 0.1, 0.16)), 0.005, c)
    return b.finish("router")


@family("camera", ("obj",), weight=0.2)
def camera(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.1, 0.15), u(rng, 0.05, 0.08), u(rng, 0.07, 0.1)
    c = DARK if rng.random() < 0.7 else metal(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, c)
    b.cylinder(h * 0.35, u(rng, 0.03, 0.08), (w * 0.1, -d / 2 + 0.005, h * 0.5), (40, 40, 45), sections=16,
               rot=rot_x(np.pi / 2))
    b.slab(-w / 2 + 0.01, -w / 2 + 0.03, -0.01, 0.01, h, h + 0.01, metal(rng))
    return b.finish("camera")


@family("cutting_board", ("obj",), weight=0.3)
def cutting_board(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, t = u(rng, 0.25, 0.45), u(rng, 0.18, 0.3), u(rng, 0.012, 0.03)
    c = wood(rng) if rng.random() < 0.7 else plastic(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, t, c)
    if rng.random() < 0.5:  # handle tab
        b.slab(w / 2, w / 2 + 0.06, -0.03, 0.03, 0, t, c)
    return b.finish("cutting board", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, t, inset=0.02)])
