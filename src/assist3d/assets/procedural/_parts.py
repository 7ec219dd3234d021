"""Parts shared by several families: legs, drawers, doors, handles, cushions, pots and foliage."""

from __future__ import annotations

import numpy as np

from ._build import Color, MeshBuilder, leaf, metal


def u(rng: np.random.Generator, lo: float, hi: float) -> float:
    """A uniform draw as a Python float."""
    return float(rng.uniform(lo, hi))


def choice(rng: np.random.Generator, options: list | tuple):
    return options[int(rng.integers(len(options)))]


def four_legs(b: MeshBuilder, rng: np.random.Generator, half_x: float, half_y: float, top: float, color: Color,
              *, thick: float | None = None, style: str | None = None) -> str:
    """Four legs from the floor to height ``top``, centred at (+-half_x, +-half_y).

    Styles: square, round, tapered (frustum) and splayed (leaning outward at the foot, kept
    inside the footprint). Returns the style used.
    """
    style = style or choice(rng, ("square", "round", "tapered", "splayed"))
    t = thick if thick is not None else u(rng, 0.025, 0.06)
    for sx in (-1.0, 1.0):
        for sy in (-1.0, 1.0):
            x, y = sx * half_x, sy * half_y
            if style == "square":
                b.slab(x - t / 2, x + t / 2, y - t / 2, y + t / 2, 0.0, top, color)
            elif style == "round":
                b.cylinder(t / 2, top, (x, y, 0.0), color, sections=10)
            elif style == "tapered":
                b.cylinder(t * 0.3, top, (x, y, 0.0), color, sections=10, top_radius=t / 2)
            else:
                lean = min(0.04, 0.4 * t)
                b.bar((x + sx * lean, y + sy * lean, 0.0), (x - sx * lean * 0.2, y - sy * lean * 0.2, top),
                        t / 2, color)
    return style


def apron(b: MeshBuilder, half_x: float, half_y: float, z0: float, z1: float, thick: float, color: Color) -> None:
    """A rail frame under a top, just inside the legs."""
    b.slab(-half_x, half_x, -half_y - thick / 2, -half_y + thick / 2, z0, z1, color)
    b.slab(-half_x, half_x, half_y - thick / 2, half_y + thick / 2, z0, z1, color)
    b.slab(-half_x - thick / 2, -half_x + thick / 2, -half_y, half_y, z0, z1, color)
    b.slab(half_x - thick / 2, half_x + thick / 2, -half_y, half_y, z0, z1, color)


def handle(b: MeshBuilder, rng: np.random.Generator, x: float, y_front: float, z: float, color: Color,
           *, style: str = "bar", length: float = 0.1, vertical: bool = False) -> None:
    """A knob or a bar handle on a front face lying at ``y_front`` (facing -y)."""
    if style == "knob":
        b.ellipsoid((0.015, 0.012, 0.015), (x, y_front - 0.01, z), color)
        return
    if vertical:
        b.slab(x - 0.008, x + 0.008, y_front - 0.025, y_front, z - length / 2, z + length / 2, color)
    else:
        b.slab(x - length / 2, x + length / 2, y_front - 0.025, y_front, z - 0.008, z + 0.008, color)


def drawer_grid(b: MeshBuilder, rng: np.random.Generator, x0: float, x1: float, z0: float, z1: float, y_front: float,
                rows: int, cols: int, color: Color, handle_color: Color | None = None, *, gap: float = 0.006) -> None:
    """Drawer fronts (thin slabs proud of the body at ``y_front``) with handles, rows x cols."""
    hc = handle_color or metal(rng)
    style = choice(rng, ("knob", "bar"))
    w = (x1 - x0) / cols
    h = (z1 - z0) / rows
    for r in range(rows):
        for c in range(cols):
            a, bb = x0 + c * w + gap / 2, x0 + (c + 1) * w - gap / 2
            lo, hi = z0 + r * h + gap / 2, z0 + (r + 1) * h - gap / 2
            b.slab(a, bb, y_front - 0.015, y_front + 0.002, lo, hi, color)
            handle(b, rng, (a + bb) / 2, y_front - 0.015, (lo + hi) / 2 + (hi - lo) * 0.15, hc, style=style,
                   length=min(0.15, 0.4 * (bb - a)))


def doors(b: MeshBuilder, rng: np.random.Generator, x0: float, x1: float, z0: float, z1: float, y_front: float,
          count: int, color: Color, handle_color: Color | None = None, *, gap: float = 0.006) -> None:
    """``count`` door panels side by side on a front face, handles near the meeting edges."""
    hc = handle_color or metal(rng)
    style = choice(rng, ("knob", "bar"))
    w = (x1 - x0) / count
    for k in range(count):
        a, bb = x0 + k * w + gap / 2, x0 + (k + 1) * w - gap / 2
        b.slab(a, bb, y_front - 0.018, y_front + 0.002, z0 + gap / 2, z1 - gap / 2, color)
        hx = bb - 0.05 if (k % 2 == 0 and count > 1) or count == 1 else a + 0.05
        hz = z0 + (z1 - z0) * (0.85 if z1 - z0 < 1.2 else 0.5) if z1 < 1.0 else (z0 + z1) / 2
        handle(b, rng, hx, y_front - 0.018, min(hz, z1 - 0.05), hc, style=style, vertical=True,
               length=min(0.2, 0.3 * (z1 - z0)))


def cushion(b: MeshBuilder, x0: float, x1: float, y0: float, y1: float, z0: float, z1: float, color: Color,
            *, round_top: bool = False) -> None:
    """An upholstered block; ``round_top`` adds a flattened half-ellipsoid crown that stays inside the block."""
    b.slab(x0, x1, y0, y1, z0, z1, color)
    if round_top:
        crown = min(0.03, 0.3 * (z1 - z0))
        b.ellipsoid(((x1 - x0) / 2 * 0.92, (y1 - y0) / 2 * 0.92, crown), ((x0 + x1) / 2, (y0 + y1) / 2, z1 - 0.001),
                    color)


def star_base(b: MeshBuilder, rng: np.random.Generator, radius: float, color: Color, wheel: Color) -> float:
    """A five-arm office-chair base with casters; returns the height of the arms' top."""
    hub_h = 0.12
    for k in range(5):
        a = 2 * np.pi * k / 5 + np.pi / 2
        d = np.array([np.cos(a), np.sin(a), 0.0])
        b.beam((0, 0, 0.09), (d[0] * radius, d[1] * radius, 0.07), 0.04, 0.03, color)
        b.ellipsoid((0.025, 0.025, 0.025), (d[0] * (radius - 0.01), d[1] * (radius - 0.01), 0.025), wheel)
    b.cylinder(0.04, hub_h, (0, 0, 0.04), color, sections=12)
    return hub_h + 0.04


def flower_pot(b: MeshBuilder, rng: np.random.Generator, r: float, h: float, color) -> None:
    """A flower pot with a rim and soil, base at z = 0."""
    top = r
    bottom = r * u(rng, 0.65, 0.9)
    b.lathe([(bottom, 0), (top, h), (top + 0.012, h), (top + 0.012, h + 0.02), (top - 0.01, h + 0.02),
             (top - 0.01, h - 0.02), (0, h - 0.02)], color, sections=20)


def foliage(b: MeshBuilder, rng: np.random.Generator, r: float, z0: float, height: float) -> None:
    kind = choice(rng, ("bush", "tree", "palm", "cactus"))
    green = leaf(rng)
    if kind == "bush":
        for _ in range(int(rng.integers(3, 7))):
            c = (rng.uniform(-r, r) * 0.6, rng.uniform(-r, r) * 0.6, z0 + rng.uniform(0.3, 0.75) * height)
            rr = u(rng, 0.45, 0.8) * max(r, height * 0.3)
            b.ellipsoid((rr, rr * u(rng, 0.8, 1.2), min(rr, height * 0.3)), c, green)
    elif kind == "tree":
        b.cylinder(max(0.01, r * 0.08), height * 0.55, (0, 0, z0 - 0.02), (90, 65, 40), sections=8)
        rr = max(r * 1.3, height * 0.25)
        b.ellipsoid((rr, rr, height * 0.3), (0, 0, z0 + height * 0.7), green, subdivisions=2)
    elif kind == "palm":
        n = int(rng.integers(5, 9))
        for k in range(n):
            a = 2 * np.pi * k / n + rng.uniform(-0.2, 0.2)
            tip = (np.cos(a) * r * 1.6, np.sin(a) * r * 1.6, z0 + height * u(rng, 0.6, 1.0))
            b.beam((0, 0, z0), tip, max(0.02, r * 0.3), 0.01, green)
    else:
        b.capsule(r * 0.55, height * 0.9, (0, 0, z0 + height * 0.45), (70, 120, 60))
        for sx in (-1, 1):
            b.capsule(r * 0.25, height * 0.35, (sx * r * 0.7, 0, z0 + height * 0.55), (70, 120, 60))
