"""More wall items (flat back at +y, built at y = 0): dartboards, planters, signs, detectors,
electrical panels, pegboards, vents and wall-hung sinks."""

from __future__ import annotations

import manifold3d as mf
import numpy as np

from ._build import DARK, WHITE, MeshBuilder, Shape, any_color, ceramic, leaf, metal, paint, plastic, rot_x, wood
from ._parts import choice, u
from ._registry import family
from .wall import FRONT, _elev


@family("dartboard", ("wall",), weight=0.2)
def dartboard(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r = u(rng, 0.2, 0.25)
    b.cylinder(r, 0.04, (0, 0, r), DARK, sections=32, rot=FRONT)
    rings = ((0.85, (230, 220, 190)), (0.6, (200, 40, 40)), (0.35, (40, 120, 60)), (0.1, (200, 40, 40)))
    for k, (f, c) in enumerate(rings):
        b.cylinder(r * f, 0.042 + 0.001 * k, (0, 0, r), c, sections=32, rot=FRONT)
    return b.finish("dartboard", elevation=_elev(1.73, 2 * r, rng))


@family("wall_planter", ("wall",), weight=0.3)
def wall_planter(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.2, 0.5), u(rng, 0.1, 0.18), u(rng, 0.1, 0.18)
    pot = ceramic(rng) if rng.random() < 0.6 else wood(rng)
    b.slab(-w / 2, w / 2, -d, 0, 0, h, pot)
    b.slab(-w / 2 - 0.01, w / 2 + 0.01, -0.01, 0, -0.04, h + 0.04, pot)
    green = leaf(rng)
    for _ in range(int(rng.integers(3, 7))):
        x = u(rng, -w / 2 + 0.04, w / 2 - 0.04)
        rr = u(rng, 0.04, 0.09)
        b.ellipsoid((rr, min(rr, d * 0.45), rr), (x, -d / 2, h + rr * 0.5), green)
    if rng.random() < 0.6:  # trailing vines
        for _ in range(int(rng.integers(1, 4))):
            x = u(rng, -w / 2 + 0.03, w / 2 - 0.03)
            b.bar((x, -d - 0.01, h), (x + rng.normal(0, 0.03), -d - 0.02, -u(rng, 0.1, 0.4)), 0.008, green, sections=5)
    return b.finish("plant", elevation=_elev(1.5, h + 0.2, rng))


@family("exit_sign", ("wall",), weight=0.2)
def exit_sign(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.3, 0.4), u(rng, 0.15, 0.2)
    green = (30, 150, 70) if rng.random() < 0.7 else (200, 40, 40)
    b.slab(-w / 2, w / 2, -0.05, 0, 0, h, WHITE)
    b.slab(-w / 2 + 0.02, w / 2 - 0.02, -0.052, -0.05, 0.02, h - 0.02, green)
    return b.finish("exit sign", elevation=float(min(2.4 - h, u(rng, 2.0, 2.2))))


@family("smoke_detector", ("wall",), weight=0.2)
def smoke_detector(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    kind = choice(rng, ("fire alarm", "thermostat"))
    if kind == "fire alarm":
        b.slab(-0.05, 0.05, -0.03, 0, 0, 0.12, (200, 30, 30))
        b.cylinder(0.03, 0.01, (0, -0.03, 0.06), WHITE, sections=16, rot=FRONT)
    else:
        w = u(rng, 0.08, 0.12)
        b.slab(-w / 2, w / 2, -0.025, 0, 0, w, WHITE if rng.random() < 0.7 else DARK)
        b.cylinder(w * 0.3, 0.006, (0, -0.025, w / 2), (60, 70, 80), sections=16, rot=FRONT)
    return b.finish(kind, elevation=u(rng, 1.4, 1.6))


@family("electrical_panel", ("wall",), weight=0.2)
def electrical_panel(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h, d = u(rng, 0.3, 0.5), u(rng, 0.4, 0.7), u(rng, 0.08, 0.12)
    c = (225, 225, 220) if rng.random() < 0.6 else metal(rng)
    b.slab(-w / 2, w / 2, -d, 0, 0, h, c)
    b.slab(-w / 2 + 0.02, w / 2 - 0.02, -d - 0.004, -d, 0.02, h - 0.02, c)
    b.slab(w / 2 - 0.05, w / 2 - 0.03, -d - 0.015, -d - 0.004, h * 0.45, h * 0.55, DARK)
    return b.finish("electrical panel", elevation=_elev(1.5, h, rng))


@family("pegboard", ("wall",), weight=0.3)
def pegboard(rng: np.random.Generator) -> Shape:
    """A board with hooks and a few hanging tools or utensils."""
    b = MeshBuilder()
    w, h = u(rng, 0.5, 1.2), u(rng, 0.4, 0.8)
    b.slab(-w / 2, w / 2, -0.02, 0, 0, h, paint(rng) if rng.random() < 0.6 else wood(rng))
    for _ in range(int(rng.integers(3, 9))):
        x, z = u(rng, -w / 2 + 0.06, w / 2 - 0.06), u(rng, 0.25, h - 0.05)
        tool = metal(rng) if rng.random() < 0.6 else plastic(rng)
        b.bar((x, -0.02, z), (x, -0.06, z + 0.015), 0.004, (120, 120, 125), sections=6)
        kind = rng.random()
        if kind < 0.4:  # a hanging handle tool: shaft and head
            length = u(rng, 0.12, 0.22)
            b.slab(x - 0.008, x + 0.008, -0.05, -0.035, z - length, z - 0.01, tool)
            b.slab(x - 0.03, x + 0.03, -0.055, -0.03, z - length - 0.03, z - length, tool)
        elif kind < 0.7:  # a pan or lid
            r = u(rng, 0.05, 0.1)
            b.cylinder(r, 0.02, (x, -0.03, z - r - 0.02), tool, sections=16, rot=FRONT)
        else:  # a coil of rope or cable
            r = u(rng, 0.04, 0.07)
            b.torus(r, 0.012, (x, -0.05, z - r), any_color(rng), sections=16, minor_sections=6, rot=rot_x(np.pi / 2))
    return b.finish("pegboard", elevation=_elev(1.3, h, rng))


@family("vent", ("wall",), weight=0.2)
def vent(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, h = u(rng, 0.2, 0.5), u(rng, 0.1, 0.3)
    c = WHITE if rng.random() < 0.7 else metal(rng)
    b.slab(-w / 2, w / 2, -0.015, 0, 0, h, c)
    n = max(3, int(h / 0.025))
    for k in range(n):
        z = 0.015 + (h - 0.03) * (k + 0.5) / n
        b.slab(-w / 2 + 0.015, w / 2 - 0.015, -0.025, -0.015, z - 0.004, z + 0.004, c)
    return b.finish("vent", elevation=choice(rng, (u(rng, 0.1, 0.3), u(rng, 2.0, 2.4 - h))))


@family("wall_sink", ("wall",), weight=0.3)
def wall_sink(rng: np.random.Generator) -> Shape:
    """A wall-hung basin (CSG bowl cut into a block) with a tap and a drain pipe below."""
    b = MeshBuilder()
    w, d, h = u(rng, 0.4, 0.65), u(rng, 0.3, 0.45), u(rng, 0.12, 0.2)
    body = mf.Manifold.cube((w, d, h), True).translate((0, -d / 2, h / 2))
    bowl = mf.Manifold.sphere(1.0, 24).scale((w / 2 - 0.04, d / 2 - 0.04, h - 0.03)).translate((0, -d / 2 - 0.01, h))
    b.manifold(body - bowl, WHITE if rng.random() < 0.7 else ceramic(rng))
    tap = metal(rng)
    b.bar((0, -0.03, h), (0, -0.03, h + 0.14), 0.012, tap)
    b.bar((0, -0.03, h + 0.14), (0, -0.12, h + 0.12), 0.01, tap)
    b.bar((0, -d / 2, 0.001), (0, -d / 2, -0.25), 0.02, tap)
    b.bar((0, -d / 2, -0.25), (0, -0.001, -0.25), 0.02, tap)
    return b.finish("sink", elevation=u(rng, 0.55, 0.65))
