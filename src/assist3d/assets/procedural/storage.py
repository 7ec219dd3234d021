"""Cabinets, dressers, nightstands, bookshelves, wardrobes, TV stands, counters and racks."""

from __future__ import annotations

import numpy as np

from ._build import MeshBuilder, Shape, material, metal, paint, rect_support, wood
from ._parts import choice, doors, drawer_grid, four_legs, u
from ._registry import family


def _carcass(b: MeshBuilder, rng: np.random.Generator, w: float, d: float, z0: float, h: float, color,
             *, plinth: bool = True) -> float:
    """A closed box body from ``z0`` to ``h`` with a recessed plinth or short legs; returns the body's bottom."""
    if z0 > 0:
        if plinth:
            b.slab(-w / 2 + 0.03, w / 2 - 0.03, -d / 2 + 0.05, d / 2 - 0.02, 0, z0, color)
        else:
            four_legs(b, rng, w / 2 - 0.04, d / 2 - 0.04, z0 + 0.005, metal(rng) if rng.random() < 0.5 else color,
                      thick=0.035, style=choice(rng, ("tapered", "round", "square")))
    b.slab(-w / 2, w / 2, -d / 2, d / 2, z0, h, color)
    return z0


def _top(w: float, d: float, h: float) -> list:
    return [rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.02)]


@family("cabinet", ("floor",), weight=1.5)
def cabinet(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.5, 1.6), u(rng, 0.35, 0.6), u(rng, 0.6, 1.2)
    body, front = material(rng), material(rng) if rng.random() < 0.4 else None
    front = front or body
    z0 = _carcass(b, rng, w, d, u(rng, 0.04, 0.15), h, body, plinth=rng.random() < 0.5)
    n = max(1, min(4, int(round(w / u(rng, 0.35, 0.5)))))
    if rng.random() < 0.4 and h > 0.75:
        split = h - u(rng, 0.15, 0.22)
        drawer_grid(b, rng, -w / 2 + 0.01, w / 2 - 0.01, split, h - 0.01, -d / 2, 1, n, front)
        doors(b, rng, -w / 2 + 0.01, w / 2 - 0.01, z0 + 0.01, split, -d / 2, n, front)
    else:
        doors(b, rng, -w / 2 + 0.01, w / 2 - 0.01, z0 + 0.01, h - 0.01, -d / 2, n, front)
    return b.finish("cabinet", supports=_top(w, d, h))


@family("dresser", ("floor",))
def dresser(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.7, 1.6), u(rng, 0.4, 0.55), u(rng, 0.75, 1.3)
    body = material(rng)
    z0 = _carcass(b, rng, w, d, u(rng, 0.05, 0.15), h - 0.03, body, plinth=rng.random() < 0.5)
    b.slab(-w / 2 - 0.01, w / 2 + 0.01, -d / 2 - 0.01, d / 2, h - 0.03, h, body)
    rows = int(rng.integers(3, 7))
    cols = 1 if w < 0.9 else int(rng.integers(1, 3))
    drawer_grid(b, rng, -w / 2 + 0.015, w / 2 - 0.015, z0 + 0.01, h - 0.04, -d / 2, rows, cols, body)
    return b.finish("dresser", supports=_top(w + 0.02, d, h))


@family("nightstand", ("floor",))
def nightstand(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.35, 0.6), u(rng, 0.3, 0.45), u(rng, 0.45, 0.65)
    body = material(rng)
    z0 = _carcass(b, rng, w, d, u(rng, 0.04, 0.15), h, body, plinth=rng.random() < 0.3)
    rows = int(rng.integers(1, 4))
    if rng.random() < 0.4:  # open niche under one drawer
        nb = z0 + (h - z0) * 0.5
        b.slab(-w / 2 + 0.02, w / 2 - 0.02, -d / 2 - 0.001, d / 2 - 0.02, nb, h - 0.17, (30, 30, 30))
        drawer_grid(b, rng, -w / 2 + 0.01, w / 2 - 0.01, h - 0.16, h - 0.01, -d / 2 - 0.001, 1, 1, body)
    else:
        drawer_grid(b, rng, -w / 2 + 0.01, w / 2 - 0.01, z0 + 0.01, h - 0.01, -d / 2, rows, 1, body)
    return b.finish("nightstand", supports=_top(w, d, h))


def _open_shelves(b: MeshBuilder, rng: np.random.Generator, w: float, d: float, h: float, n: int, color,
                  *, z_bottom: float = 0.0, back: bool = True) -> list:
    """Side panels, top, bottom, optional back and ``n`` boards; supports on every board and the top."""
    t = u(rng, 0.016, 0.03)
    b.slab(-w / 2, -w / 2 + t, -d / 2, d / 2, z_bottom, h, color)
    b.slab(w / 2 - t, w / 2, -d / 2, d / 2, z_bottom, h, color)
    b.slab(-w / 2 + t, w / 2 - t, -d / 2, d / 2, h - t, h, color)
    base = z_bottom + u(rng, 0.05, 0.1)
    b.slab(-w / 2 + t, w / 2 - t, -d / 2 + 0.01, d / 2, z_bottom, base, color)
    yb = d / 2
    if back:
        yb = d / 2 - 0.008
        b.slab(-w / 2 + t, w / 2 - t, yb, d / 2, base, h - t, color)
    levels = [base + (h - t - base) * k / (n + 1) for k in range(1, n + 1)]
    sups = []
    prev = base
    for z in levels:
        b.slab(-w / 2 + t, w / 2 - t, -d / 2 + 0.005, yb, z - t, z, color)
        sups.append(rect_support(-w / 2 + t, w / 2 - t, -d / 2 + 0.005, yb, prev, inset=0.015, clearance=z - t - prev))
        prev = z
    sups.append(rect_support(-w / 2 + t, w / 2 - t, -d / 2 + 0.005, yb, prev, inset=0.015, clearance=h - t - prev))
    sups.append(rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.015))
    return sups


@family("bookshelf", ("floor",), weight=1.5)
def bookshelf(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.5, 1.4), u(rng, 0.25, 0.4), u(rng, 0.8, 2.2)
    n = max(1, int(round(h / u(rng, 0.3, 0.42))) - 1)
    sups = _open_shelves(b, rng, w, d, h, n, material(rng), back=rng.random() < 0.8)
    return b.finish("bookshelf", supports=sups, extra={"boards": n})


@family("shelf_unit", ("floor",), weight=0.8)
def shelf_unit(rng: np.random.Generator) -> Shape:
    """A metal or wooden open rack: four posts and boards, no sides."""
    b = MeshBuilder()
    w, d, h = u(rng, 0.6, 1.2), u(rng, 0.3, 0.5), u(rng, 0.9, 1.9)
    post, board = metal(rng), (wood(rng) if rng.random() < 0.5 else metal(rng))
    p = 0.03
    for sx in (-1, 1):
        for sy in (-1, 1):
            b.slab(sx * w / 2 - (p if sx > 0 else 0), sx * w / 2 + (0 if sx > 0 else p),
                   sy * d / 2 - (p if sy > 0 else 0), sy * d / 2 + (0 if sy > 0 else p), 0, h, post)
    n = int(rng.integers(3, 6))
    zs = [0.08 + (h - 0.1) * k / (n - 1) for k in range(n)]
    sups = []
    for k, z in enumerate(zs):
        b.slab(-w / 2 + p, w / 2 - p, -d / 2, d / 2, z - 0.02, z, board)
        clear = zs[k + 1] - 0.02 - z if k + 1 < n else None
        sups.append(rect_support(-w / 2 + p, w / 2 - p, -d / 2, d / 2, z, inset=0.015, clearance=clear))
    return b.finish("shelf", supports=sups)


@family("wardrobe", ("floor",))
def wardrobe(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.8, 2.0), u(rng, 0.5, 0.65), u(rng, 1.8, 2.3)
    body = material(rng)
    z0 = _carcass(b, rng, w, d, u(rng, 0.05, 0.12), h, body)
    n = max(2, min(4, int(round(w / 0.5))))
    if rng.random() < 0.4:
        drawer_grid(b, rng, -w / 2 + 0.01, w / 2 - 0.01, z0 + 0.01, z0 + 0.35, -d / 2, 2, 1, body)
        doors(b, rng, -w / 2 + 0.01, w / 2 - 0.01, z0 + 0.36, h - 0.02, -d / 2, n, body)
    else:
        doors(b, rng, -w / 2 + 0.01, w / 2 - 0.01, z0 + 0.01, h - 0.02, -d / 2, n, body)
    return b.finish("wardrobe", supports=_top(w, d, h))


@family("tv_stand", ("floor",))
def tv_stand(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 1.0, 2.0), u(rng, 0.35, 0.5), u(rng, 0.35, 0.6)
    body, front = material(rng), material(rng)
    z0 = u(rng, 0.03, 0.15)
    _carcass(b, rng, w, d, z0, z0 + 0.02, body, plinth=False)
    t = 0.02
    b.slab(-w / 2, w / 2, -d / 2, d / 2, h - t, h, body)
    for x in (-w / 2, w / 2 - t):
        b.slab(x, x + t, -d / 2, d / 2, z0, h - t, body)
    b.slab(-w / 2 + t, w / 2 - t, d / 2 - 0.01, d / 2, z0, h - t, body)
    ow = w * u(rng, 0.3, 0.5)  # open compartment in the middle, doors at the sides
    b.slab(-ow / 2 - t, -ow / 2, -d / 2, d / 2, z0, h - t, body)
    b.slab(ow / 2, ow / 2 + t, -d / 2, d / 2, z0, h - t, body)
    doors(b, rng, -w / 2 + t, -ow / 2 - t, z0 + 0.02, h - t, -d / 2, 1, front)
    doors(b, rng, ow / 2 + t, w / 2 - t, z0 + 0.02, h - t, -d / 2, 1, front)
    sups = _top(w, d, h)
    sups.append(rect_support(-ow / 2, ow / 2, -d / 2, d / 2 - 0.01, z0 + 0.02, inset=0.015,
            clearance=h - t - z0 - 0.02))
    return b.finish("tv stand", supports=sups)


@family("kitchen_counter", ("floor",), weight=1.2)
def kitchen_counter(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    units = int(rng.integers(1, 5))
    uw = u(rng, 0.4, 0.6)
    w, d, h = units * uw, u(rng, 0.55, 0.65), u(rng, 0.86, 0.92)
    body, top = paint(rng), (choice(rng, ((60, 60, 62), (220, 218, 210), (140, 130, 120))) if rng.random() < 0.6
                             else wood(rng))
    ct = u(rng, 0.02, 0.04)
    b.slab(-w / 2 + 0.01, w / 2 - 0.01, -d / 2 + 0.07, d / 2, 0, 0.1, (40, 40, 40))
    b.slab(-w / 2, w / 2, -d / 2 + 0.03, d / 2, 0.1, h - ct, body)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, h - ct, h, top)
    for k in range(units):
        x0 = -w / 2 + k * uw
        if rng.random() < 0.35:
            drawer_grid(b, rng, x0 + 0.005, x0 + uw - 0.005, 0.11, h - ct - 0.005, -d / 2 + 0.03,
                    int(rng.integers(2, 4)),
                        1, body)
        else:
            drawer_grid(b, rng, x0 + 0.005, x0 + uw - 0.005, h - ct - 0.16, h - ct - 0.005, -d / 2 + 0.03, 1, 1, body)
            doors(b, rng, x0 + 0.005, x0 + uw - 0.005, 0.11, h - ct - 0.165, -d / 2 + 0.03, 1, body)
    return b.finish("counter", supports=_top(w, d, h), extra={"units": units})


@family("file_cabinet", ("floor",), weight=0.7)
def file_cabinet(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.38, 0.5), u(rng, 0.45, 0.7), u(rng, 0.6, 1.35)
    body = metal(rng) if rng.random() < 0.7 else paint(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h, body)
    drawer_grid(b, rng, -w / 2 + 0.01, w / 2 - 0.01, 0.03, h - 0.01, -d / 2, max(2, int(round(h / 0.32))), 1, body)
    return b.finish("file cabinet", supports=_top(w, d, h))


@family("shoe_rack", ("floor",), weight=0.5)
def shoe_rack(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.5, 1.0), u(rng, 0.25, 0.35), u(rng, 0.4, 0.9)
    c = material(rng)
    sups = _open_shelves(b, rng, w, d, h, int(rng.integers(1, 3)), c, back=False)
    return b.finish("shoe rack", supports=sups)


@family("storage_crate", ("floor", "obj"), weight=0.5)
def storage_crate(rng: np.random.Generator) -> Shape:
    """A lidded storage box or chest; fits on the floor and on big surfaces."""
    b = MeshBuilder()
    w, d, h = u(rng, 0.35, 0.9), u(rng, 0.25, 0.5), u(rng, 0.2, 0.5)
    c = material(rng) if rng.random() < 0.6 else (int(rng.integers(60, 230)), int(rng.integers(60, 230)), 200)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, 0, h - 0.03, c)
    lid = np.clip(np.array(c) * 0.8, 0, 255).astype(int)
    b.slab(-w / 2 - 0.01, w / 2 + 0.01, -d / 2 - 0.01, d / 2 + 0.01, h - 0.03, h, tuple(int(x) for x in lid))
    for sx in (-1, 1):
        b.slab(sx * (w / 2 + 0.01) - (0.02 if sx > 0 else 0), sx * (w / 2 + 0.01) + (0 if sx > 0 else 0.02),
               -0.06, 0.06, h * 0.6, h * 0.6 + 0.03, (40, 40, 40))
    return b.finish("storage box", supports=_top(w + 0.02, d + 0.02, h))
