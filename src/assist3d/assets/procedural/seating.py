"""Chairs, stools, benches, sofas, armchairs, ottomans and beds."""

from __future__ import annotations

import numpy as np

from ._build import MeshBuilder, Shape, disc_support, fabric, material, metal, plastic, rect_support, rot_x, wood
from ._parts import choice, cushion, four_legs, star_base, u
from ._registry import family


def _chair_back(b: MeshBuilder, rng: np.random.Generator, w: float, y_back: float, z0: float, z1: float,
        color) -> float:
    """Posts and a slatted, ladder or panel back at the rear edge; returns its thickness."""
    t = u(rng, 0.025, 0.04)
    y0 = y_back - t
    style = choice(rng, ("panel", "slats", "ladder"))
    for sx in (-1, 1):
        b.slab(sx * (w / 2) - (t if sx > 0 else 0), sx * (w / 2) + (0 if sx > 0 else t), y0, y_back, z0, z1, color)
    inner0, inner1 = -w / 2 + t, w / 2 - t
    if style == "panel":
        b.slab(inner0, inner1, y0 + 0.005, y_back - 0.005, z0 + (z1 - z0) * u(rng, 0.2, 0.45), z1 - 0.01, color)
    elif style == "slats":
        n = int(rng.integers(3, 7))
        zz0 = z0 + (z1 - z0) * 0.15
        sw = (inner1 - inner0) / (2 * n - 1)
        for k in range(n):
            x = inner0 + sw * (2 * k + 0.5)
            b.slab(x, x + sw, y0 + 0.005, y_back - 0.005, zz0, z1 - 0.05, color)
        b.slab(inner0, inner1, y0, y_back, z1 - 0.06, z1 - 0.01, color)
    else:
        n = int(rng.integers(2, 5))
        for k in range(n):
            z = z0 + (z1 - z0) * (k + 1) / (n + 0.5)
            b.slab(inner0, inner1, y0 + 0.005, y_back - 0.005, z - 0.025, z + 0.025, color)
    return t


@family("chair", ("floor",), weight=2.0)
def chair(rng: np.random.Generator) -> Shape:
    """Dining / side chairs: classic (slats, ladder or panel back, optional stretchers and arms),
    upholstered, or a moulded shell on metal legs."""
    b = MeshBuilder()
    w, d, sh = u(rng, 0.4, 0.52), u(rng, 0.4, 0.52), u(rng, 0.42, 0.48)
    style = choice(rng, ("classic", "classic", "upholstered", "shell"))
    frame = material(rng)
    lt = u(rng, 0.025, 0.045)
    half_x, half_y = w / 2 - lt / 2 - 0.005, d / 2 - lt / 2 - 0.005
    if style == "shell":
        shell, legs = plastic(rng), metal(rng)
        st = 0.015
        b.slab(-w / 2, w / 2, -d / 2, d / 2, sh - st, sh, shell)
        four_legs(b, rng, half_x - 0.02, half_y - 0.02, sh - st, legs, thick=0.022, style=choice(rng, ("round",
                "splayed")))
        tilt = u(rng, 0.08, 0.25)
        bh = u(rng, 0.3, 0.45)
        b.box((w, 0.015, bh), (0, d / 2 - 0.0075 + np.sin(tilt) * bh / 2, sh - 0.01 + np.cos(tilt) * bh / 2), shell,
              rot=rot_x(-tilt))
        return b.finish("chair", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2 - 0.03, sh, inset=0.03)])
    st = u(rng, 0.02, 0.06)
    seat = fabric(rng) if style == "upholstered" or rng.random() < 0.4 else wood(rng)
    b.slab(-w / 2, w / 2, -d / 2, d / 2, sh - st, sh, seat)
    four_legs(b, rng, half_x, half_y, sh - st, frame, thick=lt, style=choice(rng, ("square", "round", "tapered")))
    if rng.random() < 0.4:  # H stretcher between the legs
        z = u(rng, 0.1, 0.2)
        for sx in (-1, 1):
            b.slab(sx * half_x - 0.01, sx * half_x + 0.01, -half_y, half_y, z, z + 0.02, frame)
        b.slab(-half_x, half_x, -0.01, 0.01, z, z + 0.02, frame)
    top = sh + u(rng, 0.35, 0.55)
    if style == "upholstered":
        bt = u(rng, 0.05, 0.08)
        b.slab(-w / 2, w / 2, d / 2 + 0.02 - bt, d / 2 + 0.02, sh - st, top, seat)
    else:
        bt = _chair_back(b, rng, w, d / 2 + 0.02, sh - st, top, frame)
    x_free = w / 2
    if style == "classic" and rng.random() < 0.3:  # arms on posts above the front legs
        ah = sh + u(rng, 0.18, 0.24)
        for sx in (-1, 1):
            x = sx * half_x
            b.slab(x - 0.012, x + 0.012, -half_y - 0.012, -half_y + 0.012, sh, ah, frame)
            b.slab(x - 0.025, x + 0.025, -half_y - 0.03, d / 2 + 0.02 - bt, ah, ah + 0.025, frame)
        x_free = half_x - 0.025
    sup = rect_support(-x_free, x_free, -d / 2, d / 2 + 0.02 - bt, sh, inset=0.03)
    return b.finish("chair", supports=[sup], extra={"style": style})


@family("office_chair", ("floor",), weight=1.2)
def office_chair(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    frame, cover = (metal(rng) if rng.random() < 0.6 else plastic(rng)), fabric(rng)
    r = u(rng, 0.28, 0.34)
    hub = star_base(b, rng, r, frame, (30, 30, 30))
    sh = u(rng, 0.45, 0.52)
    b.cylinder(0.022, sh - 0.08 - hub, (0, 0, hub), (40, 40, 42), sections=10)
    w, d = u(rng, 0.45, 0.52), u(rng, 0.44, 0.5)
    b.slab(-0.12, 0.12, -0.12, 0.12, sh - 0.1, sh - 0.07, frame)
    cushion(b, -w / 2, w / 2, -d / 2, d / 2, sh - 0.07, sh, cover)
    bh = u(rng, 0.45, 0.75)
    b.slab(-0.03, 0.03, d / 2 - 0.02, d / 2 + 0.02, sh - 0.08, sh + 0.12, frame)
    b.box((w * u(rng, 0.85, 1.0), 0.07, bh), (0, d / 2 + 0.05, sh + 0.1 + bh / 2), cover, rot=None)
    if rng.random() < 0.7:  # armrests
        for sx in (-1, 1):
            x = sx * (w / 2 + 0.025)
            b.slab(x - 0.012, x + 0.012, -0.03, 0.03, sh - 0.08, sh + 0.2, frame)
            b.slab(x - 0.035, x + 0.035, -0.14, 0.12, sh + 0.2, sh + 0.23, (35, 35, 38))
    return b.finish("office chair")


@family("armchair", ("floor",))
def armchair(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    cover, leg = fabric(rng), wood(rng)
    w, d = u(rng, 0.7, 0.95), u(rng, 0.7, 0.9)
    lh = u(rng, 0.05, 0.15)
    arm_w, back_t = u(rng, 0.08, 0.18), u(rng, 0.12, 0.22)
    sh = u(rng, 0.38, 0.46)
    ah, bh = sh + u(rng, 0.15, 0.25), sh + u(rng, 0.35, 0.5)
    four_legs(b, rng, w / 2 - 0.05, d / 2 - 0.05, lh, leg, thick=0.04, style="tapered")
    b.slab(-w / 2, w / 2, -d / 2, d / 2, lh, sh - 0.1, cover)
    b.slab(-w / 2 + arm_w, w / 2 - arm_w, -d / 2, d / 2 - back_t, sh - 0.1, sh, cover)
    for sx in (-1, 1):
        x0 = sx * w / 2 - (arm_w if sx > 0 else 0)
        b.slab(x0, x0 + arm_w, -d / 2, d / 2, lh, ah, cover)
    b.slab(-w / 2, w / 2, d / 2 - back_t, d / 2, lh, bh, cover)
    sup = rect_support(-w / 2 + arm_w, w / 2 - arm_w, -d / 2, d / 2 - back_t, sh, inset=0.03)
    return b.finish("armchair", supports=[sup])


@family("sofa", ("floor",), weight=1.5)
def sofa(rng: np.random.Generator) -> Shape:
    """Two- to four-seat sofas: box, rolled or no arms, optional chaise at one end (front, -y)."""
    b = MeshBuilder()
    cover, leg = fabric(rng), (wood(rng) if rng.random() < 0.5 else metal(rng))
    seats = int(rng.integers(2, 5))
    sw = u(rng, 0.55, 0.7)
    arms = choice(rng, ("box", "box", "rolled", "none"))
    arm_w = 0.0 if arms == "none" else u(rng, 0.1, 0.25)
    w = seats * sw + 2 * arm_w
    d = u(rng, 0.8, 1.0)
    lh = u(rng, 0.04, 0.14)
    sh = u(rng, 0.4, 0.47)
    back_t = u(rng, 0.15, 0.25)
    ah, bh = sh + u(rng, 0.1, 0.25), sh + u(rng, 0.35, 0.5)
    chaise = u(rng, 0.5, 0.75) if seats >= 3 and rng.random() < 0.3 else 0.0
    side = choice(rng, (-1, 1))
    four_legs(b, rng, w / 2 - 0.06, d / 2 - 0.06, lh, leg, thick=0.04, style=choice(rng, ("square", "tapered")))
    b.slab(-w / 2, w / 2, -d / 2, d / 2, lh, sh - 0.12, cover)
    round_back = rng.random() < 0.5
    for k in range(seats):
        x0 = -w / 2 + arm_w + k * sw
        cushion(b, x0, x0 + sw, -d / 2 + 0.01, d / 2 - back_t, sh - 0.12, sh, cover)
        cushion(b, x0 + 0.004, x0 + sw - 0.004, d / 2 - back_t - 0.1, d / 2 - back_t + 0.02, sh, bh - 0.05,
                cover, round_top=round_back)
    sups = [rect_support(-w / 2 + arm_w, w / 2 - arm_w, -d / 2 + 0.01, d / 2 - back_t - 0.1, sh, inset=0.04)]
    if chaise:  # the end seat continues forward
        x0, x1 = (w / 2 - arm_w - sw, w / 2 - arm_w) if side > 0 else (-w / 2 + arm_w, -w / 2 + arm_w + sw)
        b.slab(x0 - arm_w if side < 0 else x0, x1 + arm_w if side > 0 else x1, -d / 2 - chaise, -d / 2, lh,
               sh - 0.12, cover)
        cushion(b, x0, x1, -d / 2 - chaise, -d / 2 + 0.01, sh - 0.12, sh, cover)
        b.slab((x0 + x1) / 2 - 0.02, (x0 + x1) / 2 + 0.02, -d / 2 - chaise + 0.04, -d / 2 - chaise + 0.08, 0, lh, leg)
        sups.append(rect_support(x0, x1, -d / 2 - chaise, -d / 2 + 0.01, sh, inset=0.04))
    if arms != "none":
        for sx in (-1, 1):
            x0 = sx * w / 2 - (arm_w if sx > 0 else 0)
            y0 = -d / 2 - (chaise if chaise and sx == side else 0.0)
            b.slab(x0, x0 + arm_w, y0, d / 2, lh, ah, cover)
            if arms == "rolled":
                b.cylinder(arm_w / 2 * 1.15, d / 2 - y0, (x0 + arm_w / 2, y0, ah - arm_w * 0.3), cover, sections=12,
                           rot=rot_x(-np.pi / 2))
    b.slab(-w / 2, w / 2, d / 2 - back_t, d / 2, lh, bh, cover)
    return b.finish("sofa", supports=sups, extra={"seats": seats, "arms": arms, "chaise": chaise > 0})


@family("stool", ("floor",))
def stool(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    tall = rng.random() < 0.5
    h = u(rng, 0.62, 0.8) if tall else u(rng, 0.4, 0.5)
    r = u(rng, 0.15, 0.21)
    seat, frame = (wood(rng) if rng.random() < 0.5 else fabric(rng)), material(rng)
    st = u(rng, 0.025, 0.06)
    b.cylinder(r, st, (0, 0, h - st), seat, sections=24)
    if tall and rng.random() < 0.5:  # central column on a disc
        b.cylinder(0.025, h - st, (0, 0, 0), frame, sections=10)
        b.cylinder(r * 1.1, 0.025, (0, 0, 0), frame, sections=24)
        b.torus(r * 0.8, 0.01, (0, 0, h * 0.35), frame, sections=16, minor_sections=6)
        b.bar((0, 0, h * 0.35), (r * 0.8, 0, h * 0.35), 0.008, frame)
    else:
        n = int(rng.integers(3, 5))
        rr = r * 0.75
        for k in range(n):
            a = 2 * np.pi * k / n + 0.3
            b.bar((np.cos(a) * rr * 1.25, np.sin(a) * rr * 1.25, 0), (np.cos(a) * rr * 0.85,
                    np.sin(a) * rr * 0.85, h - st),
                  0.016, frame)
        if rng.random() < 0.6:
            zr = h * u(rng, 0.25, 0.4)
            b.torus(rr * (1.25 - 0.4 * zr / (h - st)), 0.009, (0, 0, zr), frame, sections=16, minor_sections=6)
    return b.finish("stool", supports=[disc_support(0, 0, r, h, inset=0.03)])


@family("ottoman", ("floor",), weight=0.6)
def ottoman(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    cover = fabric(rng)
    h = u(rng, 0.35, 0.48)
    if rng.random() < 0.5:
        r = u(rng, 0.25, 0.45)
        b.cylinder(r, h, (0, 0, 0), cover, sections=24)
        return b.finish("ottoman", supports=[disc_support(0, 0, r, h, inset=0.04)])
    w, d = u(rng, 0.45, 1.1), u(rng, 0.4, 0.7)
    lh = u(rng, 0.0, 0.1)
    if lh > 0.03:
        four_legs(b, rng, w / 2 - 0.05, d / 2 - 0.05, lh + 0.01, wood(rng), thick=0.035, style="round")
    b.slab(-w / 2, w / 2, -d / 2, d / 2, lh, h, cover)
    return b.finish("ottoman", supports=[rect_support(-w / 2, w / 2, -d / 2, d / 2, h, inset=0.04)])


@family("bench", ("floor",))
def bench(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, d, h = u(rng, 0.9, 1.8), u(rng, 0.3, 0.45), u(rng, 0.4, 0.48)
    top, leg = wood(rng), material(rng)
    if rng.random() < 0.5:  # slats
        n = int(rng.integers(3, 6))
        sd = d / (n + (n - 1) * 0.3)
        for k in range(n):
            y0 = -d / 2 + k * sd * 1.3
            b.slab(-w / 2, w / 2, y0, y0 + sd, h - 0.03, h, top)
        b.slab(-w / 2 + 0.08, w / 2 - 0.08, -d / 2 + 0.02, d / 2 - 0.02, h - 0.07, h - 0.03, leg)
        sup = rect_support(-w / 2, w / 2, -d / 2, -d / 2 + sd, h, inset=0.01)
    else:
        b.slab(-w / 2, w / 2, -d / 2, d / 2, h - 0.04, h, top)
        sup = rect_support(-w / 2, w / 2, -d / 2, d / 2, h)
    if rng.random() < 0.5:
        four_legs(b, rng, w / 2 - 0.08, d / 2 - 0.05, h - 0.04, leg, thick=0.045)
    else:
        for sx in (-1, 1):
            x = sx * (w / 2 - 0.1)
            b.slab(x - 0.025, x + 0.025, -d / 2 + 0.02, d / 2 - 0.02, 0, h - 0.04, leg)
    return b.finish("bench", supports=[sup])


def _bed_top(b: MeshBuilder, rng: np.random.Generator, w: float, y0: float, y1: float, z: float, cover) -> list:
    """Mattress top items (pillows at +y, optional blanket); returns the free support surfaces."""
    pillow_d = u(rng, 0.3, 0.45)
    n = 1 if w < 1.2 else 2
    pw = (w - 0.1) / n
    for k in range(n):
        x0 = -w / 2 + 0.05 + k * pw
        b.ellipsoid(((pw - 0.04) / 2, pillow_d / 2 - 0.02, 0.07), (x0 + pw / 2, y1 - pillow_d / 2 - 0.02, z + 0.05),
                    (235, 235, 230))
    y_free = y1 - pillow_d - 0.04
    if rng.random() < 0.6:
        bt = u(rng, 0.02, 0.05)
        yb = y0 + (y_free - y0) * u(rng, 0.5, 1.0)
        b.slab(-w / 2 - 0.02, w / 2 + 0.02, y0 - 0.02, yb, z - 0.15, z + bt, cover)
        return [rect_support(-w / 2, w / 2, y0, yb, z + bt, inset=0.05)]
    return [rect_support(-w / 2, w / 2, y0, y_free, z, inset=0.05)]


@family("bed", ("floor",), weight=1.5)
def bed(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w = choice(rng, (0.9, 1.2, 1.4, 1.6, 1.8)) + u(rng, -0.03, 0.03)
    length = u(rng, 1.95, 2.15)
    frame, cover = material(rng), fabric(rng)
    fh = u(rng, 0.15, 0.35)
    mh = u(rng, 0.15, 0.25)
    y0, y1 = -length / 2, length / 2
    b.slab(-w / 2 - 0.03, w / 2 + 0.03, y0 - 0.03, y1, u(rng, 0.0, 0.1), fh, frame)
    if rng.random() < 0.5:
        four_legs(b, rng, w / 2 - 0.02, length / 2 - 0.05, 0.1, frame, thick=0.05, style="square")
    b.slab(-w / 2, w / 2, y0, y1, fh, fh + mh, (240, 238, 232))
    hb = u(rng, 0.8, 1.3)
    b.slab(-w / 2 - 0.05, w / 2 + 0.05, y1, y1 + u(rng, 0.04, 0.1), 0, hb, frame)
    if rng.random() < 0.4:
        b.slab(-w / 2 - 0.05, w / 2 + 0.05, y0 - 0.08, y0 - 0.03, 0, fh + mh * u(rng, 0.3, 1.2), frame)
    sup = _bed_top(b, rng, w, y0, y1, fh + mh, cover)
    return b.finish("bed", supports=sup)


@family("bunk_bed", ("floor",), weight=0.5)
def bunk_bed(rng: np.random.Generator) -> Shape:
    b = MeshBuilder()
    w, length = u(rng, 0.9, 1.0), u(rng, 1.95, 2.05)
    frame = material(rng)
    p = 0.06
    top_h = u(rng, 1.6, 1.8)
    low_z, up_z = u(rng, 0.15, 0.3), u(rng, 1.0, 1.2)
    mh = 0.15
    x0, x1, y0, y1 = -w / 2, w / 2, -length / 2, length / 2
    for sx in (x0 - p, x1):
        for sy in (y0 - p, y1):
            b.slab(sx, sx + p, sy, sy + p, 0, top_h + 0.3, frame)
    sups = []
    for z in (low_z, up_z):
        b.slab(x0, x1, y0, y1, z - 0.05, z, frame)
        b.slab(x0, x1, y0, y1, z, z + mh, (240, 238, 232))
    sups.append(rect_support(x0, x1, y0, y1, low_z + mh, inset=0.05, clearance=up_z - 0.05 - low_z - mh))
    # guard rail on the upper bunk's front side, open where the ladder is
    b.slab(x0, x1, y0 - p, y0, up_z + mh, up_z + mh + 0.25, frame)
    sups.append(rect_support(x0, x1, y0, y1, up_z + mh, inset=0.06))
    lx = choice(rng, (x0 - p - 0.05, x1 + p))
    for sy in (-length / 2 + 0.1, -length / 2 + 0.5):
        b.slab(lx, lx + 0.05, sy, sy + 0.04, 0, up_z + mh + 0.3, frame)
    for k in range(1, 5):
        b.slab(lx, lx + 0.05, -length / 2 + 0.1, -length / 2 + 0.54, k * (up_z + mh) / 5,
                k * (up_z + mh) / 5 + 0.03, frame)
    return b.finish("bunk bed", supports=sups)
