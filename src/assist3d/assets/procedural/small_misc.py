"""Electronics, toys and other small objects. Screens and fronts face -y."""

from __future__ import annotations

import numpy as np

from ._build import DARK, SCREEN, WHITE, MeshBuilder, Shape, any_color, fabric, metal, plastic, rect_support, rot_x
from ._parts import choice, u
from ._registry import family


@family("monitor", ("obj",), weight=1.2)
def monitor(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    diag = u(rng, 0.45, 0.85)
    w, h = diag * 0.87, diag * 0.49
    c = DARK if rng.random() < 0.7 else metal(rng)
    bw, bd = u(rng, 0.15, 0.25), u(rng, 0.12, 0.2)
    b.slab(-bw / 2, bw / 2, -bd / 2, bd / 2, 0, 0.015, c)
    z0 = u(rng, 0.06, 0.14)
    b.slab(-0.025, 0.025, 0.01, 0.04, 0.015, z0 + h * 0.5, c)
    b.slab(-w / 2, w / 2, -0.03, 0.0, z0, z0 + h, c)
    b.slab(-w / 2 + 0.01, w / 2 - 0.01, -0.034, -0.03, z0 + 0.015, z0 + h - 0.01, SCREEN)
    return b.finish("monitor")


@family("tv_on_foot", ("obj",), weight=0.6)
def tv_small(rng: np.random.Generator) -> Shape:
    """A TV on its own foot, for TV stands and dressers."""
    b = MeshBuilder()
    diag = u(rng, 0.6, 1.4)
    w, h = diag * 0.87, diag * 0.49
    b.slab(-w * 0.2, w * 0.2, -0.1, 0.1, 0, 0.02, DARK)
    b.slab(-0.04, 0.04, -0.01, 0.03, 0.02, 0.1, DARK)
    b.slab(-w / 2, w / 2, -0.03, 0.03, 0.07, 0.07 + h, DARK)
    b.slab(-w / 2 + 0.01, w / 2 - 0.01, -0.034, -0.03, 0.08, 0.06 + h, SCREEN)
    return b.finish("tv")


@family("keyboard", ("obj",))
def keyboard(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d = u(rng, 0.3, 0.46), u(rng, 0.11, 0.16)
    c, k = (DARK, (50, 50, 55)) if rng.random() < 0.7 else (WHITE, (225, 225, 228))
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, 0.015, c)
    rows = 5
    pitch = (d - 0.02) / rows
    for r in range(rows):  # one strip per row of keys keeps the triangle count low
        y = -d / 2 + 0.01 + (r + 0.5) * pitch
        if r == 0:
            b.slab(-w * 0.18, w * 0.18, y - pitch * 0.4, y + pitch * 0.4, 0.015, 0.024, k)
            continue
        n = int(rng.integers(10, 15))
        kw = (w - 0.02) / n
        for j in range(n):
            x = -w / 2 + 0.01 + (j + 0.5) * kw
            b.slab(x - kw * 0.42, x + kw * 0.42, y - pitch * 0.4, y + pitch * 0.4, 0.015, 0.024, k)
    return b.finish("keyboard")


@family("laptop", ("obj",))
def laptop(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d = u(rng, 0.3, 0.4), u(rng, 0.21, 0.27)
    c = metal(rng) if rng.random() < 0.6 else DARK
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, 0.018, c)
    b.slab(-w / 2 + 0.02, w / 2 - 0.02, -0.02, d / 2 - 0.02, 0.018, 0.02, DARK)
    b.slab(-0.05, 0.05, -d / 2 + 0.02, -0.03, 0.018, 0.0195, (60, 60, 62))
    ang = u(rng, 0.1, 0.45) if rng.random() < 0.85 else np.pi / 2  # open, or closed flat
    if ang < np.pi / 2:
        rot = rot_x(-ang)  # lid leans back from the hinge at +y
        hinge = np.array([0.0, d / 2, 0.018])
        b.box((w, 0.008, d), hinge + rot @ np.array([0, 0.004, d / 2]), c, rot=rot)
        b.box((w - 0.03, 0.002, d - 0.03), hinge + rot @ np.array([0, -0.001, d / 2]), SCREEN, rot=rot)
    else:
        b.slab(-w / 2, w / 2, -d / 2, d / 2, 0.018, 0.026, c)
    return b.finish("laptop")


@family("phone", ("obj",), weight=0.5)
def phone(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d = u(rng, 0.065, 0.08), u(rng, 0.13, 0.165)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, 0.008, any_color(rng) if rng.random() < 0.3 else DARK)
    b.slab(-w / 2 + 0.003, w / 2 - 0.003, -d / 2 + 0.005, d / 2 - 0.005, 0.008, 0.0085, SCREEN)
    return b.finish("phone")


@family("mouse", ("obj",), weight=0.4)
def mouse(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d = u(rng, 0.055, 0.07), u(rng, 0.09, 0.12)
    c = DARK if rng.random() < 0.6 else plastic(rng)
    hz = u(rng, 0.03, 0.04)
    b.ellipsoid((w / 2, d / 2, hz / 2), (0, 0, hz / 2), c, subdivisions=2)
    return b.finish("computer mouse")


@family("speaker", ("obj", "floor"), weight=0.6)
def speaker(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.12, 0.3), u(rng, 0.15, 0.3), u(rng, 0.2, 1.0)
    c = DARK if rng.random() < 0.5 else choice(rng, ((110, 70, 40), (235, 235, 235)))
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, c)
    n = 1 if h < 0.35 else int(rng.integers(2, 4))
    for k in range(n):
        r = min(w * 0.38, h / (2.5 * n))
        z = h * (k + 0.5) / n
        b.cylinder(r, 0.008, (0, -d / 2, z), (40, 40, 45), sections=20, rot=rot_x(np.pi / 2))
    return b.finish("speaker", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.02)] if w > 0.15 else [])


@family("printer", ("obj",), weight=0.5)
def printer(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.38, 0.5), u(rng, 0.3, 0.45), u(rng, 0.15, 0.35)
    c = WHITE if rng.random() < 0.4 else (60, 60, 65)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, c)
    b.slab(-w / 2 + 0.05, w / 2 - 0.05, -d / 2 - 0.1, -d / 2, h * 0.35, h * 0.4, c)
    b.slab(-w / 2 + 0.06, w / 2 - 0.06, -d / 2 - 0.09, -d / 2, h * 0.4, h * 0.4 + 0.004, (245, 245, 240))
    b.slab(w / 2 - 0.12, w / 2 - 0.03, -d / 2 + 0.02, -d / 2 + 0.1, h, h + 0.006, (30, 40, 50))
    return b.finish("printer", supports=[rect_support(-w / 2, w / 2 - 0.13, -d / 2, d / 2, h, inset=0.02)])


@family("computer_tower", ("floor", "obj"), weight=0.5)
def computer_tower(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.17, 0.23), u(rng, 0.38, 0.5), u(rng, 0.35, 0.5)
    c = DARK if rng.random() < 0.7 else metal(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0.02, h, c)
    for sx in (-1, 1):
        b.slab(sx * w / 2 - (0.02 if sx > 0 else 0), sx * w / 2 + (0 if sx > 0 else 0.02), -d / 2 + 0.02, d / 2 - 0.02,
               0, 0.02, DARK)
    b.cylinder(0.01, 0.004, (0, -d / 2, h - 0.05), (80, 160, 220), sections=10, rot=rot_x(np.pi / 2))
    return b.finish("computer tower", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.02)])


@family("teddy_bear", ("obj",), weight=0.6)
def teddy_bear(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    s = u(rng, 0.12, 0.4)
    c = fabric(rng) if rng.random() < 0.5 else choice(rng, ((150, 100, 60), (200, 170, 120), (240, 240, 235)))
    b.ellipsoid((0.3 * s, 0.25 * s, 0.35 * s), (0, 0, 0.35 * s), c, subdivisions=2)
    b.ellipsoid((0.22 * s, 0.2 * s, 0.2 * s), (0, -0.03 * s, 0.85 * s), c, subdivisions=2)
    b.ellipsoid((0.08 * s, 0.06 * s, 0.06 * s), (0, -0.22 * s, 0.82 * s), (220, 200, 170))
    for sx in (-1, 1):
        b.ellipsoid((0.07 * s, 0.04 * s, 0.07 * s), (sx * 0.15 * s, -0.02 * s, 1.02 * s), c)
        b.ellipsoid((0.1 * s, 0.16 * s, 0.09 * s), (sx * 0.17 * s, -0.2 * s, 0.09 * s), c)
        b.ellipsoid((0.08 * s, 0.08 * s, 0.17 * s), (sx * 0.3 * s, -0.05 * s, 0.45 * s), c)
        b.ellipsoid((0.025 * s, 0.02 * s, 0.025 * s), (sx * 0.08 * s, -0.2 * s, 0.9 * s), DARK)
    return b.finish("stuffed animal")


@family("toy_car", ("obj",), weight=0.5)
def toy_car(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    L = u(rng, 0.08, 0.35)
    w, h = L * u(rng, 0.4, 0.5), L * u(rng, 0.25, 0.35)
    c = plastic(rng)
    r = h * 0.3
    b.slab(-w / 2, w / 2, -L / 2, L / 2, r * 0.8, r * 0.8 + h * 0.45, c)
    b.slab(-w / 2 * 0.85, w / 2 * 0.85, -L * 0.2, L * 0.25, r * 0.8 + h * 0.45, h + r * 0.6, (170, 200, 220))
    for sx in (-1, 1):
        for sy in (-1, 1):
            b.cylinder(r, w * 0.12, (sx * w / 2 - (0 if sx > 0 else -w * 0.0), sy * L * 0.32, r), DARK, sections=12,
                       rot=np.array([[0, 0, sx], [0, 1, 0], [-sx, 0, 0]], dtype=float))
    return b.finish("toy")


@family("toy_blocks", ("obj",), weight=0.5)
def toy_blocks(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    s = u(rng, 0.03, 0.06)
    n = int(rng.integers(3, 10))
    heights: dict[tuple[int, int], int] = {}
    for _ in range(n):
        cell = (int(rng.integers(0, 3)), int(rng.integers(0, 3)))
        k = heights.get(cell, 0)
        heights[cell] = k + 1
        shape = rng.random()
        centre = (cell[0] * s * 1.05, cell[1] * s * 1.05)
        if shape < 0.6 or k > 0:
            b.box((s, s, s), (centre[0], centre[1], (k + 0.5) * s), plastic(rng))
        elif shape < 0.8:
            b.cylinder(s / 2, s, (centre[0], centre[1], k * s), plastic(rng), sections=12)
        else:
            b.cone(s / 2, s, (centre[0], centre[1], k * s), plastic(rng), sections=12)
            heights[cell] = 99
    return b.finish("toy")


@family("ball", ("obj", "floor"), weight=0.5)
def ball(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    kind = choice(rng, ("ball", "basketball", "soccer ball", "exercise ball"))
    r = {"ball": u(rng, 0.03, 0.1), "basketball": 0.12, "soccer ball": 0.11, "exercise ball": u(rng, 0.27, 0.37)}[kind]
    col = {"basketball": (220, 110, 40), "soccer ball": (240, 240, 240)}.get(kind) or plastic(rng)
    b.ellipsoid((r, r, r), (0, 0, r), col, subdivisions=2)
    if kind != "exercise ball":
        b.torus(r * 0.999, r * 0.02, (0, 0, r), DARK, sections=24, minor_sections=4, rot=rot_x(np.pi / 2))
    return b.finish(kind)


@family("globe", ("obj",), weight=0.3)
def globe(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r = u(rng, 0.1, 0.17)
    c = metal(rng)
    b.cylinder(r * 0.6, 0.02, (0, 0, 0), c, sections=16)
    b.cylinder(0.01, r * 0.3, (0, 0, 0.02), c, sections=8)
    zc = 0.02 + r * 0.3 + r * 1.05
    b.ellipsoid((r, r, r), (0, 0, zc), (60, 110, 170), subdivisions=2)
    for _ in range(int(rng.integers(3, 6))):  # continents: flattened blobs on the surface
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        b.ellipsoid((r * 0.35, r * 0.35, r * 0.35), np.array([0, 0, zc]) + n * r * 0.72, (90, 140, 70))
    b.torus(r * 1.08, 0.006, (0, 0, zc), c, sections=24, minor_sections=4, rot=rot_x(np.pi / 2))
    return b.finish("globe")


@family("headphones", ("obj",), weight=0.3)
def headphones(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r = u(rng, 0.08, 0.1)
    c = DARK if rng.random() < 0.6 else plastic(rng)
    for sx in (-1, 1):
        b.cylinder(0.045, 0.03, (sx * r - (0.03 if sx > 0 else 0), 0, 0.045), c, sections=16,
                   rot=np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], dtype=float))
    arc = np.linspace(0, np.pi, 8)
    pts = [(-np.cos(a) * r, 0.0, 0.09 + np.sin(a) * r) for a in arc]
    for p0, p1 in zip(pts[:-1], pts[1:]):
        b.bar(p0, p1, 0.008, c, sections=6)
    return b.finish("headphones")


@family("remote", ("obj",), weight=0.3)
def remote(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    kind = choice(rng, ("remote control", "game controller"))
    c = DARK if rng.random() < 0.7 else plastic(rng)
    if kind == "remote control":
        w, d = u(rng, 0.04, 0.06), u(rng, 0.14, 0.22)
        b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, 0.02, c)
        for k in range(int(rng.integers(3, 7))):
            b.cylinder(0.006, 0.004, (0, -d / 2 + 0.03 + k * 0.02, 0.02), any_color(rng), sections=8)
    else:
        b.ellipsoid((0.07, 0.04, 0.02), (0, 0, 0.02), c, subdivisions=2)
        for sx in (-1, 1):
            b.ellipsoid((0.025, 0.035, 0.02), (sx * 0.055, 0.025, 0.02), c)
    return b.finish(kind)
