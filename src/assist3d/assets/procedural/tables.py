"""Tables and desks."""

from __future__ import annotations

import numpy as np

from ._build import MeshBuilder, Shape, disc_support, material, metal, rect_support, wood
from ._parts import apron, choice, drawer_grid, four_legs, u
from ._registry import family


@family("table_rect", ("floor",), weight=1.5)
def table_rect(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.8, 1.8), u(rng, 0.6, 1.0), u(rng, 0.70, 0.78)
    t = u(rng, 0.02, 0.05)
    top, leg = wood(rng), material(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, h - t, h, top)
    inset = u(rng, 0.04, 0.12)
    lt = u(rng, 0.03, 0.07)
    four_legs(b, rng, w / 2 - inset, d / 2 - inset, h - t, leg, thick=lt)
    if rng.random() < 0.6:
        apron(b, w / 2 - inset, d / 2 - inset, h - t - u(rng, 0.06, 0.12), h - t, 0.02, leg)
    return b.finish("table", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h)])


@family("table_dining", ("floor",), weight=1.2)
def table_dining(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 1.4, 2.4), u(rng, 0.8, 1.1), u(rng, 0.72, 0.78)
    t = u(rng, 0.03, 0.06)
    top = wood(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, h - t, h, top)
    if rng.random() < 0.5:  # trestle: two slab ends and a stretcher
        for sx in (-1, 1):
            x = sx * (w / 2 - u(rng, 0.15, 0.3))
            b.slab(x - 0.04, x + 0.04, -d / 2 + 0.1, d / 2 - 0.1, 0.0, 0.05, top)
            b.slab(x - 0.03, x + 0.03, -0.08, 0.08, 0.0, h - t, top)
        b.slab(-w / 2 + 0.3, w / 2 - 0.3, -0.03, 0.03, 0.25, 0.33, top)
    else:
        four_legs(b, rng, w / 2 - 0.08, d / 2 - 0.08, h - t, top, thick=u(rng, 0.05, 0.09))
        apron(b, w / 2 - 0.08, d / 2 - 0.08, h - t - 0.1, h - t, 0.025, top)
    return b.finish("dining table", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h)])


@family("table_round", ("floor",))
def table_round(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    r, h = u(rng, 0.4, 0.75), u(rng, 0.70, 0.76)
    t = u(rng, 0.025, 0.05)
    top, base = wood(rng), material(rng)
    b.cylinder(r, t, (0, 0, h - t), top, sections=32)
    if rng.random() < 0.5:  # pedestal
        b.cylinder(u(rng, 0.03, 0.07), h - t, (0, 0, 0), base, sections=12)
        b.cylinder(u(rng, 0.2, 0.8) * r, 0.03, (0, 0, 0), base, sections=24, top_radius=0.05)
    else:
        n = int(rng.integers(3, 5))
        for k in range(n):
            a = 2 * np.pi * k / n
            rr = r * 0.7
            b.bar((np.cos(a) * rr * 1.1, np.sin(a) * rr * 1.1, 0), (np.cos(a) * rr * 0.8, np.sin(a) * rr * 0.8, h - t),
                  0.022, base)
    return b.finish("round table", supports=[disc_support(0, 0, r, h, n=16)])


@family("table_coffee", ("floor",), weight=1.2)
def table_coffee(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.8, 1.4), u(rng, 0.45, 0.8), u(rng, 0.35, 0.48)
    t = u(rng, 0.02, 0.05)
    top, leg = wood(rng), material(rng)
    sup = [rect_support(-w / 2, w / 2, -d / 2, d / 2, h)]
    if rng.random() < 0.3:  # glass top on a frame
        b.slab(-w / 2, w / 2, -d / 2, d / 2, h - t, h, (170, 195, 205))
    else:
        b.slab(-w / 2, w / 2, -d / 2, d / 2, h - t, h, top)
    inset = u(rng, 0.03, 0.08)
    lt = u(rng, 0.03, 0.06)
    four_legs(b, rng, w / 2 - inset, d / 2 - inset, h - t, leg, thick=lt, style=choice(rng, ("square", "round")))
    if rng.random() < 0.5:  # lower shelf between the legs
        sz = u(rng, 0.08, 0.15)
        st = 0.02
        b.slab(-w / 2 + inset - lt / 2, w / 2 - inset + lt / 2, -d / 2 + inset - lt / 2, d / 2 - inset + lt / 2,
               sz, sz + st, top)
        sup.append(rect_support(-w / 2 + inset + lt / 2, w / 2 - inset - lt / 2, -d / 2 + inset + lt / 2,
                                d / 2 - inset - lt / 2, sz + st, inset=0.02, clearance=h - t - sz - st))
    return b.finish("coffee table", supports=sup)


@family("table_side", ("floor",))
def table_side(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    h = u(rng, 0.45, 0.65)
    top, body = wood(rng), material(rng)
    if rng.random() < 0.4:  # round end table on a central column
        r = u(rng, 0.2, 0.35)
        b.cylinder(r, 0.025, (0, 0, h - 0.025), top, sections=24)
        b.cylinder(0.025, h - 0.025, (0, 0, 0), body, sections=10)
        b.cylinder(r * 0.7, 0.02, (0, 0, 0), body, sections=24)
        return b.finish("end table", supports=[disc_support(0, 0, r, h)])
    w, d = u(rng, 0.35, 0.6), u(rng, 0.35, 0.55)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, h - 0.025, h, top)
    four_legs(b, rng, w / 2 - 0.03, d / 2 - 0.03, h - 0.025, body, thick=0.035, style=choice(rng, ("square",
            "tapered")))
    if rng.random() < 0.5:
        b.slab(-w / 2 + 0.04, w / 2 - 0.04, -d / 2 + 0.03, d / 2 - 0.03, h - 0.16, h - 0.025, body)
        drawer_grid(b, rng, -w / 2 + 0.05, w / 2 - 0.05, h - 0.155, h - 0.03, -d / 2 + 0.03, 1, 1, top)
    return b.finish("end table", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h)])


@family("desk", ("floor",), weight=1.5)
def desk(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 1.0, 1.8), u(rng, 0.55, 0.85), u(rng, 0.72, 0.77)
    t = u(rng, 0.02, 0.04)
    top, body, hc = material(rng), material(rng), metal(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, h - t, h, top)
    style = choice(rng, ("pedestal", "legs", "panels"))
    if style == "pedestal":
        pw = u(rng, 0.35, 0.45)
        side = choice(rng, (-1, 1))
        x0 = side * (w / 2 - 0.01) - (pw if side > 0 else 0)
        x1 = x0 + pw
        b.slab(x0, x1, -d / 2 + 0.02, d / 2 - 0.01, 0, h - t, body)
        drawer_grid(b, rng, x0 + 0.01, x1 - 0.01, 0.05, h - t - 0.01, -d / 2 + 0.02, int(rng.integers(2, 5)), 1,
                body, hc)
        ox = -side * (w / 2 - 0.03)
        b.slab(ox - 0.02, ox + 0.02, -d / 2 + 0.03, d / 2 - 0.01, 0, h - t, body)
    elif style == "legs":
        four_legs(b, rng, w / 2 - 0.05, d / 2 - 0.05, h - t, body, thick=0.04, style=choice(rng, ("square", "round")))
        b.slab(-w / 2 + 0.05, w / 2 - 0.05, d / 2 - 0.07, d / 2 - 0.05, h - t - 0.3, h - t, body)
    else:
        for sx in (-1, 1):
            b.slab(sx * (w / 2 - 0.01) - 0.015, sx * (w / 2 - 0.01) + 0.015, -d / 2 + 0.02, d / 2 - 0.01, 0,
                    h - t, body)
        b.slab(-w / 2 + 0.02, w / 2 - 0.02, d / 2 - 0.04, d / 2 - 0.02, 0.15, h - t, body)
    return b.finish("desk", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h)])


@family("desk_corner", ("floor",), weight=0.6)
def desk_corner(rng: np.random.Generator) -> Shape:
    """An L-shaped desk: a main run along x and a return along -y on one side."""
    b = MeshBuilder()
    w, d, h = u(rng, 1.3, 1.8), u(rng, 0.55, 0.75), u(rng, 0.72, 0.76)
    rl, rd = u(rng, 0.9, 1.4), u(rng, 0.45, 0.6)
    t = 0.03
    top, body = material(rng), metal(rng)
    side = choice(rng, (-1, 1))
    b.slab(-w / 2, w / 2, 0.0, d, h - t, h, top)
    xr0, xr1 = (w / 2 - rd, w / 2) if side > 0 else (-w / 2, -w / 2 + rd)
    b.slab(xr0, xr1, -rl + d, 0.0, h - t, h, top)
    for x, y in ((-w / 2 + 0.03, d - 0.03), (w / 2 - 0.03, d - 0.03), (-side * (w / 2 - 0.03), 0.03),
                 ((xr0 + xr1) / 2 - side * (rd / 2 - 0.03), -rl + d + 0.03),
                 ((xr0 + xr1) / 2 + side * (rd / 2 - 0.03), -rl + d + 0.03)):
        b.slab(x - 0.025, x + 0.025, y - 0.025, y + 0.025, 0, h - t, body)
    return b.finish("desk", supports=[rect_support(-w / 2, w / 2, 0.0, d, h),
                                      rect_support(xr0, xr1, -rl + d, 0.0, h)])
