"""Relation scores, vectorised over candidate poses.

Every relation kind maps a batch of candidate poses of the object being placed (and, for kinds
with a target, the target's box) to a score in [0, 1]. A relation counts as *satisfied* when its
score is at least :data:`SATISFIED` (0.5); a ``hard`` relation keeps only candidates that satisfy
it, a soft one only ranks them. Definitions (``gap`` = distance between the axis-aligned boxes
around the two footprints, 0 when they touch; ``local`` = the candidate's centre in the target's
frame, whose front is -y and whose own left is +x):

* ``near``: 1 for gap <= 0.5 m, falling linearly to 0 at 1.5 m (satisfied: gap <= 1 m).
* ``far``: 0 for gap <= 0.5 m, rising linearly to 1 at 1.5 m (satisfied: gap >= 1 m).
* ``in_front_of`` / ``behind``: the centre lies beyond the target's front (back) face
  (local y < -depth/2, resp. > +depth/2), times a lateral factor (1 while |local x| is within
  the target's half width, falling to 0 one metre further out) and a proximity factor
  (1 - gap / 2 m, clipped).
* ``left_of`` / ``right_of``: the same along local x: the target's own left (+x, as seen by
  someone sitting on it and looking out of its front) or right (-x). For wall objects,
  left/right are along the wall. ``side_of``: the better of the two.
* ``around``: a ``near`` that prefers contact (1 for gap <= 0.1 m, falling linearly to 0 at
  1.9 m; satisfied, like ``near``, up to 1 m) x face_to: chairs around a table, pulled up to it
  where there is room.
* ``center_aligned``: 1 when the centre is within 5 cm of one of the target's two centre lines,
  falling linearly to 0 at 0.5 m.
* ``face_to``: 1 when the ray from the candidate's front hits the target's footprint (lateral
  offset of the target's centre from the ray at most its smaller half extent, target ahead),
  otherwise 0.5 x max(0, cos) of the angle between the front and the direction to the target.
* ``face_same_as``: max(0, cos(yaw difference)): 1 for the same orientation, 0 at 90 degrees.
* ``edge``: 1 when the object's back is within 5 cm of a wall, falling to 0 at 1 m.
* ``middle``: the footprint's clearance to the walls / 1 m, clipped (satisfied: >= 0.5 m).
* ``height``: 1 when the base height is in [value0, value1], falling to 0 0.5 m outside.
* ``above``: 1 when the candidate's centre lies over the target's footprint (in plan view) and
  its base is at or above the target's top; the plan-view factor falls to 0 one metre away.
* ``on``: always 1 (the on-top search only produces poses on the support).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.geometry import box_gap, rotated_half_extents

SATISFIED = 0.5

__all__ = ["SATISFIED", "Candidates", "TargetBox", "relation_score"]


@dataclass
class Candidates:
    """A batch of candidate poses of one object: (n,) float64 arrays, plus its size.

    ``back_gap`` is the distance of the back face to the nearest wall and ``wall_clear`` the
    clearance of the footprint to the walls (both (n,), metres; NaN where unknown).
    """

    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    z: np.ndarray
    size: tuple[float, float, float]
    back_gap: np.ndarray | None = None
    wall_clear: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.x)

    def take(self, idx: np.ndarray) -> "Candidates":
        pick = (lambda a: None if a is None else a[idx])
        return Candidates(self.x[idx], self.y[idx], self.yaw[idx], self.z[idx], self.size,
                          pick(self.back_gap), pick(self.wall_clear))

    @staticmethod
    def concat(parts: list["Candidates"], size: tuple[float, float, float]) -> "Candidates":
        if not parts:
            e = np.zeros(0)
            return Candidates(e, e, e, e, size)

        def cat(name: str) -> np.ndarray | None:
            arrs = [getattr(p, name) for p in parts]
            if any(a is None for a in arrs):
                return None
            return np.concatenate(arrs)

        return Candidates(np.concatenate([p.x for p in parts]), np.concatenate([p.y for p in parts]),
                          np.concatenate([p.yaw for p in parts]), np.concatenate([p.z for p in parts]), size,
                          cat("back_gap"), cat("wall_clear"))


@dataclass(frozen=True)
class TargetBox:
    """The box of a relation target (an already placed object)."""

    x: float
    y: float
    yaw: float
    width: float
    depth: float
    z0: float
    z1: float

    @property
    def half_extents(self) -> tuple[float, float]:
        hx, hy = rotated_half_extents(self.width, self.depth, self.yaw)
        return float(hx), float(hy)


def _lin(v: np.ndarray, zero: float, one: float) -> np.ndarray:
    """Linear ramp: 0 at ``zero``, 1 at ``one`` (either order), clipped to [0, 1]."""
    return np.clip((v - zero) / (one - zero), 0.0, 1.0)


def _gap(c: Candidates, t: TargetBox) -> np.ndarray:
    hx, hy = rotated_half_extents(c.size[0], c.size[1], c.yaw)
    thx, thy = t.half_extents
    return box_gap(c.x, c.y, hx, hy, t.x, t.y, thx, thy)


def _local(c: Candidates, t: TargetBox) -> tuple[np.ndarray, np.ndarray]:
    dx, dy = c.x - t.x, c.y - t.y
    ct, st = np.cos(t.yaw), np.sin(t.yaw)
    return ct * dx + st * dy, -st * dx + ct * dy


def _directional(c: Candidates, t: TargetBox, axis: str, sign: float) -> np.ndarray:
    lx, ly = _local(c, t)
    along, across = (lx, ly) if axis == "x" else (ly, lx)
    half_along = t.width / 2 if axis == "x" else t.depth / 2
    half_across = t.depth / 2 if axis == "x" else t.width / 2
    beyond = (sign * along) > half_along - 1e-6
    lateral = 1.0 - _lin(np.abs(across), half_across, half_across + 1.0)
    lateral = np.where(np.abs(across) <= half_across, 1.0, lateral)
    proximity = 1.0 - np.clip(_gap(c, t) / 2.0, 0.0, 1.0)
    return np.where(beyond, lateral * proximity, 0.0)


def _face_to(c: Candidates, t: TargetBox) -> np.ndarray:
    fx, fy = np.sin(c.yaw), -np.cos(c.yaw)  # world front of the candidate
    vx, vy = t.x - c.x, t.y - c.y
    along = fx * vx + fy * vy
    perp = np.abs(fx * vy - fy * vx)
    dist = np.maximum(np.hypot(vx, vy), 1e-9)
    r = min(t.width, t.depth) / 2
    hit = (along > 0) & (perp <= r)
    return np.where(hit, 1.0, 0.5 * np.maximum(0.0, along / dist))


def relation_score(kind: str, c: Candidates, target: TargetBox | None, value: tuple[float, ...] = ()) -> np.ndarray:
    """(n,) float64 scores in [0, 1] of relation ``kind`` for candidate poses ``c``.

    Kinds with a target need ``target``; an unknown kind raises ``KeyError``.
    """
    n = len(c)
    if kind == "on":
        return np.ones(n)
    if kind == "edge":
        if c.back_gap is None:
            return np.zeros(n)
        return 1.0 - _lin(np.nan_to_num(c.back_gap, nan=1e9), 0.05, 1.0)
    if kind == "middle":
        if c.wall_clear is None:
            return np.zeros(n)
        return _lin(np.nan_to_num(c.wall_clear, nan=0.0), 0.0, 1.0)
    if kind == "height":
        lo, hi = (float(value[0]), float(value[1])) if len(value) >= 2 else (0.0, np.inf)
        out = np.maximum(lo - c.z, c.z - hi)
        return 1.0 - _lin(np.maximum(out, 0.0), 0.0, 0.5)
    if target is None:
        raise KeyError(f"relation {kind!r} needs a target")
    if kind == "near":
        return 1.0 - _lin(_gap(c, target), 0.5, 1.5)
    if kind == "far":
        return _lin(_gap(c, target), 0.5, 1.5)
    if kind == "in_front_of":
        return _directional(c, target, "y", -1.0)
    if kind == "behind":
        return _directional(c, target, "y", 1.0)
    if kind == "left_of":
        return _directional(c, target, "x", 1.0)
    if kind == "right_of":
        return _directional(c, target, "x", -1.0)
    if kind == "side_of":
        return np.maximum(_directional(c, target, "x", 1.0), _directional(c, target, "x", -1.0))
    if kind == "around":
        return (1.0 - _lin(_gap(c, target), 0.1, 1.9)) * _face_to(c, target)
    if kind == "center_aligned":
        lx, ly = _local(c, target)
        return 1.0 - _lin(np.minimum(np.abs(lx), np.abs(ly)), 0.05, 0.5)
    if kind == "face_to":
        return _face_to(c, target)
    if kind == "face_same_as":
        return np.maximum(0.0, np.cos(c.yaw - target.yaw))
    if kind == "above":
        lx, ly = _local(c, target)
        ox = np.maximum(np.abs(lx) - target.width / 2, 0.0)
        oy = np.maximum(np.abs(ly) - target.depth / 2, 0.0)
        plan = 1.0 - _lin(np.hypot(ox, oy), 0.0, 1.0)
        return np.where(c.z >= target.z1 - 1e-6, plan, 0.0)
    raise KeyError(f"unknown relation kind {kind!r}")
