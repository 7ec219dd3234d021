"""More household items: showers, ladders, ironing boards, cleaners, coolers, cribs, guitars,
blinds, calendars, toilet paper, pen holders and staplers."""

from __future__ import annotations

import numpy as np

from ._build import (DARK, GLASS, WHITE, MeshBuilder, Shape, any_color, fabric, material, metal, paint, plastic,
                     rect_support, rot_x, rot_z, wood)
from ._parts import choice, u
from ._registry import family
from .wall import _elev


@family("shower_curtain", ("wall",), weight=0.5)
def shower_curtain(rng: np.random.Generator) -> Shape:
    """A curtain on a rod held out from the wall by two brackets, hanging almost to the floor."""
    b = MeshBuilder()
    w, h = u(rng, 0.8, 1.6), u(rng, 1.6, 1.9)
    reach = u(rng, 0.6, 0.9)
    rod = metal(rng)
    for sx in (-1, 1):
        b.bar((sx * w / 2, 0.0, h), (sx * w / 2, -reach, h), 0.01, rod)
    b.bar((-w / 2 - 0.01, -reach, h), (w / 2 + 0.01, -reach, h), 0.012, rod)
    cloth = fabric(rng) if rng.random() < 0.5 else (235, 240, 245)
    folds = int(rng.integers(5, 12))
    x = np.linspace(-w / 2, w / 2, folds * 4 + 1)
    y = -reach + 0.03 * np.sin(np.linspace(0, folds * 2 * np.pi, len(x)))
    for k in range(len(x) - 1):
        seg = np.array([x[k + 1] - x[k], y[k + 1] - y[k]])
        length = float(np.hypot(*seg)) + 0.004
        b.box((length, 0.006, h - 0.06), ((x[k] + x[k + 1]) / 2, (y[k] + y[k + 1]) / 2, (h - 0.06) / 2 + 0.02), cloth,
              rot=rot_z(float(np.arctan2(seg[1], seg[0]))))
    return b.finish("shower curtain", elevation=u(rng, 0.0, max(0.0, 2.3 - h)))


@family("shower", ("floor",), weight=0.4)
def shower(rng: np.random.Generator) -> Shape:
    """A square shower tray with glass panels on the front and one side, and a shower head at the back."""
    b = MeshBuilder()
    w, d, h = u(rng, 0.8, 1.0), u(rng, 0.8, 1.0), u(rng, 1.9, 2.1)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, 0.06, WHITE)
    frame = metal(rng)
    side = choice(rng, (-1, 1))
    b.slab(-w / 2, w / 2, -d / 2, -d / 2 + 0.01, 0.06, h, GLASS)
    b.slab(side * w / 2 - (0.01 if side > 0 else 0), side * w / 2 + (0 if side > 0 else 0.01), -d / 2 + 0.01, d / 2,
           0.06, h, GLASS)
    b.slab(-w / 2, w / 2, -d / 2, -d / 2 + 0.015, h - 0.03, h, frame)
    b.bar((0, d / 2 - 0.02, 0.9), (0, d / 2 - 0.02, h - 0.1), 0.012, frame)
    b.bar((0, d / 2 - 0.02, h - 0.1), (0, d / 2 - 0.25, h - 0.1), 0.012, frame)
    b.cylinder(0.1, 0.02, (0, d / 2 - 0.25, h - 0.13), frame, sections=16)
    return b.finish("shower")


@family("ladder", ("floor",), weight=0.4)
def ladder(rng: np.random.Generator) -> Shape:
    """A folding step ladder (two A-frame legs) seen from the side along x."""
    b = MeshBuilder()
    h, w = u(rng, 0.6, 1.6), u(rng, 0.4, 0.55)
    spread = h * u(rng, 0.3, 0.4)
    c = metal(rng) if rng.random() < 0.7 else wood(rng)
    for sx in (-1, 1):
        x = sx * (w / 2 - 0.02)
        b.beam((x, -spread / 2, 0), (x, -0.02, h), 0.04, 0.025, c)
        b.beam((x, spread / 2, 0), (x, 0.02, h), 0.04, 0.025, c)
    n = max(2, int(h / 0.25))
    for k in range(1, n + 1):
        z = h * k / (n + 0.3)
        y = -spread / 2 * (1 - z / h)
        b.slab(-w / 2 + 0.02, w / 2 - 0.02, y - 0.06, y + 0.02, z - 0.02, z, c)
    b.slab(-w / 2, w / 2, -0.12, 0.08, h, h + 0.03, plastic(rng))
    return b.finish("ladder")


@family("ironing_board", ("floor",), weight=0.3)
def ironing_board(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    L, d, h = u(rng, 1.1, 1.4), u(rng, 0.3, 0.4), u(rng, 0.75, 0.95)
    top = fabric(rng)
    b.slab(-L / 2 + d / 2, L / 2 - 0.05, -d / 2, d / 2, h - 0.02, h, top)
    b.cylinder(d / 2, 0.02, (-L / 2 + d / 2, 0, h - 0.02), top, sections=16)
    legs = metal(rng)
    for sy in (-1, 1):
        b.bar((-L * 0.25, sy * d * 0.35, 0), (L * 0.2, sy * d * 0.3, h - 0.02), 0.01, legs)
        b.bar((L * 0.25, sy * d * 0.35, 0), (-L * 0.2, sy * d * 0.3, h - 0.02), 0.01, legs)
    return b.finish("ironing board")


@family("vacuum_cleaner", ("floor",), weight=0.3)
def vacuum_cleaner(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    c = plastic(rng)
    if rng.random() < 0.5:  # upright
        h = u(rng, 0.9, 1.15)
        b.slab(-0.15, 0.15, -0.15, 0.05, 0, 0.08, c)
        b.slab(-0.1, 0.1, -0.02, 0.12, 0.08, 0.55, c)
        b.bar((0, 0.05, 0.55), (0, 0.08, h - 0.05), 0.015, DARK)
        b.beam((-0.08, 0.08, h - 0.04), (0.08, 0.08, h - 0.04), 0.03, 0.03, DARK)
    else:  # robot
        r = u(rng, 0.16, 0.18)
        b.cylinder(r, 0.08, (0, 0, 0.005), c, sections=24)
        b.cylinder(0.04, 0.015, (0, -r * 0.4, 0.085), DARK, sections=12)
        b.cylinder(r * 0.95, 0.005, (0, 0, 0), DARK, sections=24)
    return b.finish("vacuum cleaner")


@family("water_cooler", ("floor",), weight=0.3)
def water_cooler(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.3, 0.35), u(rng, 0.3, 0.38), u(rng, 0.9, 1.05)
    c = WHITE if rng.random() < 0.6 else metal(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, c)
    b.slab(-0.08, 0.08, -d / 2 - 0.05, -d / 2, h * 0.6, h * 0.62, DARK)
    b.slab(-0.08, 0.08, -d / 2 - 0.03, -d / 2, h * 0.75, h * 0.82, DARK)
    r = 0.13
    b.lathe([(r, h), (r, h + 0.38), (r * 0.9, h + 0.42), (0.03, h + 0.44)], (150, 190, 230), sections=20)
    return b.finish("water cooler")


@family("fire_extinguisher", ("floor", "obj"), weight=0.3)
def fire_extinguisher(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.06, 0.09), u(rng, 0.35, 0.6)
    red = (200, 30, 30)
    b.lathe([(r, 0.0), (r, h * 0.85), (r * 0.6, h * 0.95), (0.02, h)], red, sections=16)
    b.cylinder(0.015, 0.06, (0, 0, h), DARK, sections=8)
    b.beam((0, 0, h + 0.05), (0.0, -0.1, h + 0.03), 0.02, 0.01, DARK)
    b.bar((0, 0, h + 0.03), (0.0, r + 0.02, h * 0.5), 0.007, DARK)
    return b.finish("fire extinguisher")


@family("mini_fridge", ("floor",), weight=0.3)
def mini_fridge(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.44, 0.55), u(rng, 0.45, 0.55), u(rng, 0.5, 0.85)
    c = WHITE if rng.random() < 0.5 else choice(rng, ((30, 30, 32), (170, 170, 175), (200, 60, 50)))
    b.slab(-w / 2, w / 2, -d / 2 + 0.03, d / 2, 0.02, h, c)
    b.slab(-w / 2, w / 2, -d / 2, -d / 2 + 0.03, 0.03, h, c)
    b.slab(-w / 2 + 0.03, w / 2 - 0.03, -d / 2 + 0.05, d / 2 - 0.05, 0, 0.02, DARK)
    b.slab(w / 2 - 0.05, w / 2 - 0.03, -d / 2 - 0.025, -d / 2, h * 0.5, h - 0.08, metal(rng))
    return b.finish("mini fridge", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.03)])


@family("crib", ("floor",), weight=0.3)
def crib(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 1.2, 1.45), u(rng, 0.65, 0.8), u(rng, 0.85, 1.0)
    c = wood(rng) if rng.random() < 0.5 else paint(rng)
    mz = u(rng, 0.25, 0.45)
    for sx in (-1, 1):
        for sy in (-1, 1):
            b.slab(sx * w / 2 - (0.04 if sx > 0 else 0), sx * w / 2 + (0 if sx > 0 else 0.04),
                   sy * d / 2 - (0.04 if sy > 0 else 0), sy * d / 2 + (0 if sy > 0 else 0.04), 0, h, c)
    b.slab(-w / 2 + 0.04, w / 2 - 0.04, -d / 2 + 0.04, d / 2 - 0.04, mz - 0.03, mz, c)
    b.slab(-w / 2 + 0.04, w / 2 - 0.04, -d / 2 + 0.04, d / 2 - 0.04, mz, mz + 0.1, (240, 238, 232))
    for sy in (-1, 1):  # long sides: rails and bars
        y0 = sy * d / 2 - (0.03 if sy > 0 else 0)
        for z in (mz - 0.06, h - 0.04):
            b.slab(-w / 2 + 0.04, w / 2 - 0.04, y0, y0 + 0.03, z, z + 0.04, c)
        n = int((w - 0.08) / 0.08)
        for k in range(n):
            x = -w / 2 + 0.04 + (k + 0.5) * (w - 0.08) / n
            b.slab(x - 0.012, x + 0.012, y0 + 0.003, y0 + 0.027, mz - 0.02, h - 0.04, c)
    for sx in (-1, 1):  # short sides: panels
        x0 = sx * w / 2 - (0.03 if sx > 0 else 0)
        b.slab(x0, x0 + 0.03, -d / 2 + 0.04, d / 2 - 0.04, mz - 0.06, h - 0.02, c)
    return b.finish("crib", supports=[rect_support(-w / 2 + 0.04, w / 2 - 0.04, -d / 2 + 0.04, d / 2 - 0.04, mz + 0.1,
                                                   inset=0.04)])


@family("guitar", ("floor",), weight=0.3)
def guitar(rng: np.random.Generator) -> Shape:
    """A guitar upright on a small stand, its face toward -y."""
    b = MeshBuilder()
    body = choice(rng, ((180, 120, 60), (120, 60, 30), (200, 40, 40), (30, 30, 32), (230, 200, 150)))
    s = u(rng, 0.9, 1.1)
    t = 0.09 * s
    stand = metal(rng)
    b.beam((-0.18, -0.15, 0), (0, 0.05, 0.35), 0.02, 0.02, stand)
    b.beam((0.18, -0.15, 0), (0, 0.05, 0.35), 0.02, 0.02, stand)
    b.cylinder(0.22 * s, t, (0, 0, 0.28 * s), body, sections=20, rot=rot_x(np.pi / 2), radius_y=0.26 * s)
    b.cylinder(0.17 * s, t, (0, 0, 0.62 * s), body, sections=20, rot=rot_x(np.pi / 2), radius_y=0.18 * s)
    b.cylinder(0.045 * s, t * 1.05, (0, 0.001, 0.5 * s), DARK, sections=16, rot=rot_x(np.pi / 2))
    b.slab(-0.025, 0.025, -t * 0.7, -t * 0.3, 0.7 * s, 1.0 * s, (90, 60, 35))
    b.slab(-0.04, 0.04, -t * 0.75, -t * 0.25, 1.0 * s, 1.15 * s, (60, 40, 25))
    return b.finish("guitar")


@family("blinds", ("wall",), weight=0.3)
def blinds(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.6, 1.6), u(rng, 0.8, 1.6)
    c = WHITE if rng.random() < 0.5 else (wood(rng) if rng.random() < 0.5 else paint(rng))
    b.slab(-w / 2, w / 2, -0.06, 0, h - 0.05, h, c)
    n = int(h / 0.05)
    for k in range(n):
        z = h - 0.06 - k * 0.05
        b.box((w - 0.02, 0.045, 0.004), (0, -0.035, z), c)
    for sx in (-0.3, 0.3):
        b.slab(sx * w - 0.002, sx * w + 0.002, -0.04, -0.03, h - 0.06 - (n - 1) * 0.05, h - 0.05, (200, 200, 200))
    return b.finish("blinds", elevation=_elev(1.6, h, rng))


@family("calendar", ("wall",), weight=0.3)
def calendar(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.25, 0.4), u(rng, 0.35, 0.6)
    b.slab(-w / 2, w / 2, -0.004, 0, 0, h, (245, 245, 240))
    b.slab(-w / 2 + 0.01, w / 2 - 0.01, -0.006, -0.004, h * 0.5, h - 0.02, any_color(rng))
    for r in range(5):
        b.slab(-w / 2 + 0.02, w / 2 - 0.02, -0.0055, -0.004, 0.02 + r * h * 0.09, 0.024 + r * h * 0.09, DARK)
    return b.finish("calendar", elevation=_elev(1.5, h, rng))


@family("toilet_paper", ("obj",), weight=0.3)
def toilet_paper(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    n = int(rng.integers(1, 4))
    r, w = u(rng, 0.05, 0.065), u(rng, 0.095, 0.11)
    for k in range(n):  # rolls standing on end, side by side
        x = (k - (n - 1) / 2) * 2.05 * r
        b.lathe([(0.02, 0.0), (r, 0.0), (r, w), (0.02, w), (0.02, w - 0.002), (0.018, w - 0.002), (0.018, 0.002),
                 (0.02, 0.002)], WHITE, base=(x, 0, 0), sections=20)
    return b.finish("toilet paper")


@family("pen_holder", ("obj",), weight=0.3)
def pen_holder(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.03, 0.045), u(rng, 0.08, 0.12)
    c = material(rng) if rng.random() < 0.5 else plastic(rng)
    b.lathe([(r, 0.0), (r, h), (r - 0.003, h), (r - 0.003, 0.004), (0.0, 0.004)], c, sections=16)
    for _ in range(int(rng.integers(2, 7))):
        a, d = rng.uniform(0, 2 * np.pi), rng.uniform(0, r * 0.6)
        tip = (np.cos(a) * d + rng.normal(0, 0.01), np.sin(a) * d + rng.normal(0, 0.01), h + u(rng, 0.03, 0.08))
        b.bar((np.cos(a) * d, np.sin(a) * d, 0.005), tip, 0.004, any_color(rng), sections=6)
    return b.finish("pen holder")


@family("stapler", ("obj",), weight=0.2)
def stapler(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    L, w = u(rng, 0.12, 0.18), u(rng, 0.035, 0.05)
    c = choice(rng, (DARK, (180, 30, 30), (40, 60, 140), (160, 160, 165)))
    b.slab(-w / 2, w / 2, -L / 2, L / 2, 0, 0.012, DARK)
    b.box((w * 0.9, L * 0.95, 0.022), (0, 0, 0.027), c, rot=rot_x(-0.06))
    return b.finish("stapler")
