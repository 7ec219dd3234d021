"""Wall items. Each hangs with its flat back at +y (built at y = 0, everything in front at y < 0)
and suggests the height of its base above the floor (``elevation``), keeping its top below 2.4 m."""

from __future__ import annotations

import numpy as np

from ._build import (DARK, GLASS, MIRROR, SCREEN, WHITE, MeshBuilder, Shape, any_color, fabric, material, metal, paint,
                     plastic, rect_support, rot_x, rot_z, wood)
from ._parts import choice, doors, u
from ._registry import family

FRONT = rot_x(np.pi / 2)  # maps +z to -y: a z-axis primitive on the wall faces the room


def _elev(centre: float, h: float, rng: np.random.Generator, top: float = 2.4) -> float:
    return float(max(0.0, min(centre + rng.uniform(-0.1, 0.1) - h / 2, top - h)))


def _frame(b: MeshBuilder, w: float, h: float, f: float, depth: float, color) -> None:
    """A rectangular frame of bar width ``f`` around (-w/2..w/2, 0..h), from y = -depth to 0."""
    b.slab(-w / 2, w / 2, -depth, 0, 0, f, color)
    b.slab(-w / 2, w / 2, -depth, 0, h - f, h, color)
    b.slab(-w / 2, -w / 2 + f, -depth, 0, f, h - f, color)
    b.slab(w / 2 - f, w / 2, -depth, 0, f, h - f, color)


@family("picture", ("wall",), weight=2.0)
def picture(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.25, 1.2), u(rng, 0.25, 1.0)
    f = u(rng, 0.015, 0.06)
    _frame(b, w, h, f, u(rng, 0.02, 0.04), material(rng) if rng.random() < 0.7 else DARK)
    b.slab(-w / 2 + f, w / 2 - f, -0.012, 0, f, h - f, any_color(rng))
    for _ in range(int(rng.integers(0, 5))):  # painted blocks on the canvas
        x0, x1 = sorted(rng.uniform(-w / 2 + f + 0.01, w / 2 - f - 0.01, 2))
        z0, z1 = sorted(rng.uniform(f + 0.01, h - f - 0.01, 2))
        if x1 - x0 > 0.01 and z1 - z0 > 0.01:
            b.slab(float(x0), float(x1), -0.015, -0.01, float(z0), float(z1), any_color(rng))
    return b.finish("picture", elevation=_elev(1.5, h, rng))


@family("poster", ("wall",), weight=0.6)
def poster(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.3, 0.7), u(rng, 0.4, 1.0)
    b.slab(-w / 2, w / 2, -0.003, 0, 0, h, any_color(rng))
    for _ in range(int(rng.integers(1, 4))):
        z0 = u(rng, 0.05, h * 0.7)
        b.slab(-w / 2 + 0.03, w / 2 - 0.03, -0.005, -0.002, z0, z0 + u(rng, 0.03, h * 0.25), any_color(rng))
    return b.finish("poster", elevation=_elev(1.5, h, rng))


@family("mirror", ("wall",))
def mirror(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    fc = material(rng)
    if rng.random() < 0.4:
        r = u(rng, 0.2, 0.45)
        b.cylinder(r, 0.025, (0, 0, r), fc, sections=32, rot=FRONT)
        b.cylinder(r - u(rng, 0.015, 0.05), 0.03, (0, 0, r), MIRROR, sections=32, rot=FRONT)
        h = 2 * r
    else:
        w, h = u(rng, 0.4, 1.0), u(rng, 0.5, 1.4)
        f = u(rng, 0.01, 0.05)
        _frame(b, w, h, f, 0.03, fc)
        b.slab(-w / 2 + f, w / 2 - f, -0.02, 0, f, h - f, MIRROR)
    return b.finish("mirror", elevation=_elev(1.45, h, rng))


@family("wall_shelf", ("wall",), weight=1.5)
def wall_shelf(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d = u(rng, 0.4, 1.2), u(rng, 0.15, 0.3)
    c, br = material(rng), metal(rng)
    n = int(rng.integers(1, 4))
    gap = u(rng, 0.25, 0.35)
    t = u(rng, 0.015, 0.03)
    sups = []
    if rng.random() < 0.5:  # boards on brackets
        for k in range(n):
            z = 0.1 + k * gap
            b.slab(-w / 2, w / 2, -d, 0, z - t, z, c)
            for sx in (-1, 1):
                x = sx * (w / 2 - 0.08)
                b.slab(x - 0.01, x + 0.01, -d * 0.8, 0, z - t - 0.012, z - t, br)
                b.slab(x - 0.01, x + 0.01, -0.012, 0, z - t - 0.1, z - t, br)
            sups.append(rect_support(-w / 2, w / 2, -d, 0, z, inset=0.015,
                                     clearance=gap - t if k + 1 < n else None))
        h = 0.1 + (n - 1) * gap
    else:  # box shelf with sides
        h = n * gap + t
        b.slab(-w / 2, -w / 2 + t, -d, 0, 0, h, c)
        b.slab(w / 2 - t, w / 2, -d, 0, 0, h, c)
        for k in range(n + 1):
            b.slab(-w / 2 + t, w / 2 - t, -d, 0, k * gap, k * gap + t, c)
            sups.append(rect_support(-w / 2 + t, w / 2 - t, -d, 0, k * gap + t, inset=0.015,
                                     clearance=gap - t if k < n else None))
    return b.finish("shelf", supports=sups, elevation=_elev(1.3, h, rng))


@family("clock", ("wall",))
def clock(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r = u(rng, 0.12, 0.25)
    rim, face = material(rng), (WHITE if rng.random() < 0.7 else any_color(rng))
    sections = choice(rng, (8, 12, 32, 32))
    b.cylinder(r, u(rng, 0.03, 0.05), (0, 0, r), rim, sections=sections, rot=FRONT)
    b.cylinder(r * 0.9, 0.05 + 0.005, (0, 0, r), face, sections=sections, rot=FRONT)
    for k in range(12):
        a = 2 * np.pi * k / 12
        b.box((0.008, 0.004, r * 0.1), (np.sin(a) * r * 0.78, -0.057, r + np.cos(a) * r * 0.78), DARK,
              rot=np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]))
    for length, ang in ((0.5, rng.uniform(0, 2 * np.pi)), (0.75, rng.uniform(0, 2 * np.pi))):
        L = r * length
        b.box((0.01, 0.004, L), (np.sin(ang) * L / 2, -0.062, r + np.cos(ang) * L / 2), DARK,
              rot=np.array([[np.cos(ang), 0, np.sin(ang)], [0, 1, 0], [-np.sin(ang), 0, np.cos(ang)]]))
    return b.finish("clock", elevation=_elev(1.9, 2 * r, rng))


@family("tv_wall", ("wall",), weight=1.2)
def tv_wall(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    diag = u(rng, 0.8, 1.9)
    w, h = diag * 0.87, diag * 0.49
    body = DARK if rng.random() < 0.8 else metal(rng)
    b.slab(-0.15, 0.15, -0.03, 0, h * 0.3, h * 0.7, DARK)  # wall mount
    b.slab(-w / 2, w / 2, -0.03 - u(rng, 0.03, 0.06), -0.03, 0, h, body)
    b.slab(-w / 2 + 0.012, w / 2 - 0.012, -0.03 - 0.065, -0.05, 0.012, h - 0.012, SCREEN)
    return b.finish("tv", elevation=_elev(1.3, h, rng))


@family("radiator", ("wall",))
def radiator(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    n = int(rng.integers(6, 25))
    h, d = u(rng, 0.4, 0.8), u(rng, 0.06, 0.12)
    c = WHITE if rng.random() < 0.7 else paint(rng)
    pitch = u(rng, 0.045, 0.08)
    w = n * pitch
    b.slab(-w / 2, w / 2, -0.03, -0.01, 0.05, h - 0.05, c)
    for k in range(n):
        x = -w / 2 + (k + 0.5) * pitch
        b.slab(x - 0.012, x + 0.012, -d - 0.03, -0.03, 0, h, c)
    b.slab(-0.02, 0.02, -0.03, 0, h * 0.4, h * 0.6, metal(rng))
    b.cylinder(0.015, 0.06, (w / 2 + 0.03, -0.05, 0.02), metal(rng), sections=10)
    return b.finish("radiator", elevation=u(rng, 0.08, 0.2))


@family("wall_cabinet", ("wall",))
def wall_cabinet(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.4, 1.2), u(rng, 0.28, 0.38), u(rng, 0.5, 0.8)
    c = material(rng)
    b.slab(-w / 2, w / 2, -d + 0.02, 0, 0, h, c)
    kind = "kitchen cabinet" if rng.random() < 0.6 else "cabinet"
    if rng.random() < 0.25:  # mirrored bathroom cabinet
        kind = "bathroom cabinet"
        b.slab(-w / 2 + 0.01, w / 2 - 0.01, -d, -d + 0.02, 0.01, h - 0.01, MIRROR)
    else:
        doors(b, rng, -w / 2 + 0.005, w / 2 - 0.005, 0.005, h - 0.005, -d + 0.02, 1 if w < 0.6 else 2, c)
    return b.finish(kind, supports=[rect_support(-w / 2, w / 2, -d + 0.02, 0, h, inset=0.02)],
                    elevation=_elev(1.75, h, rng, top=2.3))


@family("whiteboard", ("wall",), weight=0.8)
def whiteboard(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.9, 2.4), u(rng, 0.6, 1.2)
    rim = metal(rng)
    _frame(b, w, h, 0.02, 0.025, rim)
    b.slab(-w / 2 + 0.02, w / 2 - 0.02, -0.015, 0, 0.02, h - 0.02, (245, 246, 248))
    b.slab(-w / 2 + 0.05, w / 2 - 0.05, -0.08, 0, 0, 0.02, rim)
    cls = "whiteboard"
    if rng.random() < 0.3:
        cls = "blackboard"
        b.slab(-w / 2 + 0.02, w / 2 - 0.02, -0.017, -0.014, 0.02, h - 0.02, (30, 50, 40))
    return b.finish(cls, elevation=_elev(1.45, h, rng))


@family("bulletin_board", ("wall",), weight=0.6)
def bulletin_board(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.5, 1.2), u(rng, 0.4, 0.9)
    _frame(b, w, h, 0.02, 0.025, wood(rng))
    b.slab(-w / 2 + 0.02, w / 2 - 0.02, -0.015, 0, 0.02, h - 0.02, (190, 150, 105))
    for _ in range(int(rng.integers(2, 8))):
        pw, ph = u(rng, 0.08, 0.21), u(rng, 0.1, 0.28)
        x = u(rng, -w / 2 + 0.03 + pw / 2, w / 2 - 0.03 - pw / 2)
        z = u(rng, 0.03, h - 0.03 - ph)
        b.slab(x - pw / 2, x + pw / 2, -0.018, -0.015, z, z + ph, (245, 245,
                240) if rng.random() < 0.6 else any_color(rng))
    return b.finish("bulletin board", elevation=_elev(1.45, h, rng))


@family("air_conditioner", ("wall",), weight=0.6)
def air_conditioner(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.7, 1.1), u(rng, 0.18, 0.25), u(rng, 0.25, 0.32)
    c = WHITE
    b.slab(-w / 2, w / 2, -d + 0.05, 0, 0.05, h, c)
    b.cylinder(0.05, w, (-w / 2, -d + 0.05, 0.05), c, sections=16,
               rot=np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], dtype=float))
    b.slab(-w / 2, w / 2, -d + 0.05, 0, 0, 0.05, c)
    b.slab(-w / 2 + 0.05, w / 2 - 0.05, -d + 0.045, -d + 0.06, 0.06, 0.09, (170, 170, 175))
    return b.finish("air conditioner", elevation=float(min(2.4 - h, u(rng, 1.95, 2.15))))


@family("coat_hooks", ("wall",), weight=0.6)
def coat_hooks(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    n = int(rng.integers(3, 7))
    w = n * u(rng, 0.1, 0.16)
    c, hk = wood(rng), metal(rng)
    b.slab(-w / 2, w / 2, -0.02, 0, 0, 0.1, c)
    for k in range(n):
        x = -w / 2 + (k + 0.5) * w / n
        b.bar((x, -0.02, 0.05), (x, -0.08, 0.09), 0.008, hk)
    board_z = _elev(1.7, 0.1, rng)
    if rng.random() < 0.4:  # a coat hanging from a hook
        x = -w / 2 + 0.5 * w / n
        b.slab(x - 0.2, x + 0.2, -0.16, -0.04, -0.8, 0.06, fabric(rng))
        board_z -= 0.8
    return b.finish("coat rack", elevation=board_z)


@family("curtain", ("wall",), weight=1.0)
def curtain(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.6, 1.6), u(rng, 1.2, 2.2)
    folds = int(rng.integers(4, 10))
    amp = u(rng, 0.02, 0.05)
    x = np.linspace(-w / 2, w / 2, folds * 4 + 1)
    y = -0.08 - amp * (1 + np.sin(np.linspace(0, folds * 2 * np.pi, len(x))))
    cloth = fabric(rng)
    for k in range(len(x) - 1):  # one thin panel per segment of the folded hem line
        seg = np.array([x[k + 1] - x[k], y[k + 1] - y[k]])
        ang = float(np.arctan2(seg[1], seg[0]))
        length = float(np.hypot(*seg)) + 0.004
        b.box((length, 0.008, h - 0.05), ((x[k] + x[k + 1]) / 2, (y[k] + y[k + 1]) / 2, (h - 0.05) / 2), cloth,
              rot=rot_z(ang))
    b.bar((-w / 2 - 0.05, -0.1, h - 0.02), (w / 2 + 0.05, -0.1, h - 0.02), 0.012, metal(rng))
    for sx in (-1, 1):
        b.slab(sx * (w / 2 + 0.03) - 0.01, sx * (w / 2 + 0.03) + 0.01, -0.1, 0, h - 0.04, h, metal(rng))
    return b.finish("curtain", elevation=float(max(0.0, min(u(rng, 0.0, 0.8), 2.4 - h))))


@family("wall_lamp", ("wall",), weight=0.6)
def wall_lamp(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    c, shade = metal(rng), (fabric(rng) if rng.random() < 0.5 else (245, 240, 220))
    b.cylinder(0.05, 0.02, (0, 0, 0.05), c, sections=16, rot=FRONT)
    reach = u(rng, 0.1, 0.25)
    b.bar((0, -0.02, 0.05), (0, -reach, 0.12), 0.008, c)
    r = u(rng, 0.06, 0.12)
    b.cylinder(r, u(rng, 0.1, 0.18), (0, -reach, 0.1), shade, sections=16, top_radius=r * u(rng, 0.5, 0.9))
    return b.finish("light", elevation=_elev(1.8, 0.25, rng))


@family("towel_rack", ("wall",), weight=0.5)
def towel_rack(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w = u(rng, 0.4, 0.7)
    c = metal(rng)
    for sx in (-1, 1):
        b.cylinder(0.02, 0.015, (sx * w / 2, 0, 0.3), c, sections=10, rot=FRONT)
        b.bar((sx * w / 2, -0.01, 0.3), (sx * w / 2, -0.07, 0.3), 0.008, c)
    b.bar((-w / 2, -0.07, 0.3), (w / 2, -0.07, 0.3), 0.01, c)
    tw = w * u(rng, 0.5, 0.85)
    col = fabric(rng)
    b.slab(-tw / 2, tw / 2, -0.085, -0.08, u(rng, 0.0, 0.1), 0.31, col)
    b.slab(-tw / 2, tw / 2, -0.06, -0.055, u(rng, 0.05, 0.15), 0.31, col)
    b.slab(-tw / 2, tw / 2, -0.085, -0.055, 0.31, 0.32, col)
    return b.finish("towel", elevation=_elev(1.2, 0.32, rng))


@family("wall_switch", ("wall",), weight=0.4)
def wall_switch(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    kind = choice(rng, ("light switch", "power outlet"))
    n = int(rng.integers(1, 3))
    c = WHITE if rng.random() < 0.8 else plastic(rng)
    s = 0.08
    b.slab(-n * s / 2, n * s / 2, -0.01, 0, 0, s, c)
    for k in range(n):
        x = -n * s / 2 + (k + 0.5) * s
        if kind == "light switch":
            b.slab(x - 0.02, x + 0.02, -0.016, -0.01, s / 2 - 0.02, s / 2 + 0.02, c)
        else:
            b.cylinder(0.022, 0.006, (x, -0.01, s / 2), (200, 200, 200), sections=16, rot=FRONT)
    return b.finish(kind, elevation=1.05 if kind == "light switch" else u(rng, 0.2, 0.35))


@family("dispenser", ("wall",), weight=0.4)
def dispenser(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    kind = choice(rng, ("paper towel dispenser", "soap dispenser"))
    w, d, h = ((u(rng, 0.25, 0.32), u(rng, 0.1, 0.14), u(rng, 0.3, 0.4)) if kind == "paper towel dispenser"
               else (u(rng, 0.08, 0.12), u(rng, 0.07, 0.1), u(rng, 0.15, 0.22)))
    c = WHITE if rng.random() < 0.6 else plastic(rng)
    b.slab(-w / 2, w / 2, -d, 0, 0.02, h, c)
    b.slab(-w / 2 + 0.01, w / 2 - 0.01, -d + 0.01, -0.01, 0, 0.02, GLASS if kind == "soap dispenser" else c)
    return b.finish(kind, elevation=_elev(1.25, h, rng))
