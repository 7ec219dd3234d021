"""Room shells sized like real scans: rectangular or L-shaped footprints with doors and windows.

``sample_room(cfg, rng)`` draws a :class:`~assist3d.core.contracts.Room`: a counter-clockwise floor
polygon with its minimum corner at the origin, a wall height, and non-overlapping door and window
openings on walls long enough to hold them. Wall ``i`` runs from vertex ``i`` to vertex ``i+1``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace

import numpy as np

from ..config import RoomConfig
from ..core.contracts import Opening, Room
from ..core.errors import ConfigError

log = logging.getLogger(__name__)

DOOR_WIDTH = (0.8, 1.0)  # m
DOOR_HEIGHT = (2.0, 2.1)  # m, bottom at the floor
WINDOW_WIDTH = (0.6, 1.6)  # m
WINDOW_BOTTOM = (0.8, 1.0)  # m
WINDOW_TALL = (1.0, 1.5)  # m, window height before clipping below the ceiling
CORNER_MARGIN = 0.15  # m kept free between an opening and a wall's ends
OPENING_GAP = 0.2  # m between two openings of the same wall
TRIES_PER_OPENING = 30
L_CUT_FRACTION = (0.3, 0.5)  # the cut-out corner spans this fraction of each side


def polygon_area(polygon) -> float:
    """Signed area (shoelace; positive for counter-clockwise), m^2."""
    p = np.asarray(polygon, dtype=np.float64)
    x, y = p[:, 0], p[:, 1]
    return float(0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)))


def room_walls(room: Room) -> np.ndarray:
    """(n, 2, 2) float64: wall i from polygon vertex i to vertex i+1."""
    p = np.asarray(room.polygon, dtype=np.float64)
    return np.stack([p, np.roll(p, -1, axis=0)], axis=1)


def wall_lengths(room: Room) -> np.ndarray:
    """(n,) float64 wall lengths, m."""
    w = room_walls(room)
    return np.linalg.norm(w[:, 1] - w[:, 0], axis=1)


def opening_segment(room: Room, opening: Opening) -> np.ndarray:
    """(2, 2) float64: the opening's start and end points on the floor plan."""
    a, b = room_walls(room)[opening.wall]
    d = (b - a) / max(float(np.linalg.norm(b - a)), 1e-12)
    c = a + d * opening.offset
    return np.stack([c - d * opening.width / 2, c + d * opening.width / 2])


def _check_cfg(cfg: RoomConfig) -> None:
    if cfg.area_min > cfg.area_max:
        raise ConfigError(f"room.area_min ({cfg.area_min}) is larger than room.area_max ({cfg.area_max})")
    if cfg.height_min > cfg.height_max:
        raise ConfigError(f"room.height_min ({cfg.height_min}) is larger than room.height_max ({cfg.height_max})")
    for name in ("doors", "windows"):
        lo, hi = getattr(cfg, name)
        if lo < 0 or lo > hi:
            raise ConfigError(f"room.{name}: expected an inclusive range [lo, hi] with 0 <= lo <= hi, got {lo, hi}")
    if cfg.height_min < DOOR_HEIGHT[0] + 0.1:
        raise ConfigError(f"room.height_min ({cfg.height_min} m) leaves no room for a {DOOR_HEIGHT[0]} m door; "
                          f"use at least {DOOR_HEIGHT[0] + 0.1} m")


def _footprint(cfg: RoomConfig, rng: np.random.Generator) -> list[tuple[float, float]]:
    area = float(rng.uniform(cfg.area_min, cfg.area_max))
    aspect = float(rng.uniform(1.0, cfg.aspect_max))
    l_shape = bool(rng.random() < cfg.l_shape_prob)
    fa, fb = (float(v) for v in rng.uniform(*L_CUT_FRACTION, size=2))
    box_area = area / (1.0 - fa * fb) if l_shape else area
    w = math.sqrt(box_area * aspect)
    d = box_area / w
    if rng.random() < 0.5:
        w, d = d, w
    if l_shape:
        cw, cd = fa * w, fb * d
        pts = [(0.0, 0.0), (w, 0.0), (w, d - cd), (w - cw, d - cd), (w - cw, d), (0.0, d)]
    else:
        pts = [(0.0, 0.0), (w, 0.0), (w, d), (0.0, d)]
    # rotate by a random multiple of 90 degrees (keeps the winding), then move the min corner to 0
    k = int(rng.integers(4))
    p = np.asarray(pts)
    for _ in range(k):
        p = np.stack([-p[:, 1], p[:, 0]], axis=1)
    p -= p.min(axis=0)
    start = int(rng.integers(len(p)))
    p = np.roll(p, -start, axis=0)
    return [(round(float(x), 6), round(float(y), 6)) for x, y in p]


def _place_openings(polygon, height: float, cfg: RoomConfig, rng: np.random.Generator) -> tuple[Opening, ...]:
    p = np.asarray(polygon)
    lengths = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    n_doors = int(rng.integers(cfg.doors[0], cfg.doors[1] + 1))
    n_windows = int(rng.integers(cfg.windows[0], cfg.windows[1] + 1))
    taken: dict[int, list[tuple[float, float]]] = {}
    out: list[Opening] = []
    for kind in ["door"] * n_doors + ["window"] * n_windows:
        for _ in range(TRIES_PER_OPENING):
            if kind == "door":
                width = float(rng.uniform(*DOOR_WIDTH))
                bottom = 0.0
                top = min(float(rng.uniform(*DOOR_HEIGHT)), height - 0.1)
            else:
                width = float(rng.uniform(*WINDOW_WIDTH))
                bottom = float(rng.uniform(*WINDOW_BOTTOM))
                top = min(bottom + float(rng.uniform(*WINDOW_TALL)), height - 0.15)
            fits = lengths >= width + 2 * CORNER_MARGIN
            if not fits.any():
                continue
            prob = np.where(fits, lengths, 0.0)
            wall = int(rng.choice(len(lengths), p=prob / prob.sum()))
            half = width / 2
            offset = float(rng.uniform(CORNER_MARGIN + half, lengths[wall] - CORNER_MARGIN - half))
            lo, hi = offset - half, offset + half
            if any(lo < b + OPENING_GAP and a - OPENING_GAP < hi for a, b in taken.get(wall, [])):
                continue
            taken.setdefault(wall, []).append((lo, hi))
            out.append(Opening(kind, wall, round(offset, 6), round(width, 6), round(bottom, 6), round(top, 6)))
            break
        else:
            log.debug("room: no free wall span for a %s after %d tries; skipped", kind, TRIES_PER_OPENING)
    return tuple(out)


def sample_room(cfg: RoomConfig, rng: np.random.Generator) -> Room:
    """A random room shell.

    Floor area in [area_min, area_max] m^2, bounding-box aspect <= aspect_max, wall height in
    [height_min, height_max] m, rectangular or (with ``l_shape_prob``) L-shaped; doors (0.8-1.0 m
    wide, 2.0-2.1 m high) and windows (bottom 0.8-1.0 m, top below the ceiling) on walls long enough
    for them, never overlapping each other.
    """
    _check_cfg(cfg)
    polygon = _footprint(cfg, rng)
    height = round(float(rng.uniform(cfg.height_min, cfg.height_max)), 6)
    openings = _place_openings(polygon, height, cfg, rng)
    return Room(polygon=tuple(polygon), height=height, openings=openings, ceiling=cfg.ceiling)


DOOR_CLOSED_P = 0.4  # probability that a filled door is closed
DOOR_MIN_OPEN_DEG = 15.0  # an ajar door is open at least this far
LEAF_MARGIN = 0.05  # m kept between an open leaf's far edge and the end of the door's clearance zone


def fill_openings(room: Room, first_id: int, door_clearance: float, rng: np.random.Generator) -> Room:
    """``room`` with every opening filled (``room.fill_openings``): instance ids ``first_id``,
    ``first_id + 1``, ... in opening order; each door hinged at a random side and closed (probability
    0.4) or ajar into the room at a uniform angle from 15 degrees up to where the leaf still ends
    ``LEAF_MARGIN`` inside the door's clearance zone (placement keeps that zone free, so an open leaf
    never meets an object); closed when the zone is too shallow for 15 degrees."""
    out = []
    for k, o in enumerate(room.openings):
        leaf, hinge = 0.0, 0
        if o.kind == "door":
            hinge = int(rng.integers(2))
            reach = (door_clearance - LEAF_MARGIN) / max(o.width, 1e-6)
            max_deg = math.degrees(math.asin(min(1.0, reach))) if reach > 0 else 0.0
            if rng.random() >= DOOR_CLOSED_P and max_deg >= DOOR_MIN_OPEN_DEG:
                leaf = round(float(rng.uniform(DOOR_MIN_OPEN_DEG, max_deg)), 6)
        out.append(replace(o, instance=first_id + k, leaf_deg=leaf, hinge=hinge))
    return replace(room, openings=tuple(out))

