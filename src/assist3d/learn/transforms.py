"""Point-cloud training transforms, one pipeline for every model (numpy, an explicit random generator).

A recipe is a :class:`Compose` of transforms applied in order to :class:`Points` (float64 coordinates and
colours, and the input rows they came from); each transform draws its random numbers from the generator it
is given, in a fixed order, so a recipe is a pure function of its input and the generator's state. The
CPU segmenter's recipe (:func:`assist3d.learn.segmenter.data.augment`: crop, thin, centre, mirror, tilt and
turn, scale, floor shift, sensor jitter, colour drop and jitter) and the Mask3D-style model's
(:func:`assist3d.learn.engine.augment.augment_points`: centre and offset, mirrors, elastic warp, per-axis
scale, rotation, colour jitter and shift) are two lists of these transforms. A new recipe is a new list;
a new transform is a class with ``__call__(points, rng) -> Points``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Sequence

import numpy as np


@dataclass(frozen=True)
class Points:
    """``coord`` (N, 3) and ``color`` (N, 3) float64 (colour 0..255), ``rows`` (N,) the input row of each point."""

    coord: np.ndarray
    color: np.ndarray
    rows: np.ndarray

    @classmethod
    def of(cls, coord: np.ndarray, color: np.ndarray) -> Points:
        return cls(coord.astype(np.float64), color.astype(np.float64), np.arange(len(coord)))

    def take(self, rows: np.ndarray) -> Points:
        return Points(self.coord[rows], self.color[rows], self.rows[rows])

    def colors_u8(self) -> np.ndarray:
        return np.clip(self.color, 0, 255).astype(np.uint8)


Transform = Callable[[Points, np.random.Generator], Points]


class Compose:
    """The transforms of a recipe, applied in order."""

    def __init__(self, transforms: Sequence[Transform]) -> None:
        self.transforms = list(transforms)

    def __call__(self, p: Points, rng: np.random.Generator) -> Points:
        for t in self.transforms:
            p = t(p, rng)
        return p


def rotation_matrix(ax: float, ay: float, az: float) -> np.ndarray:
    """``Rz @ Ry @ Rx`` for angles in radians about x, y and z."""
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


@dataclass(frozen=True)
class CropSquare:
    """A random ``edge`` m square window in x, y that stays inside the scene (its middle when the scene is
    smaller); 0 keeps everything."""

    edge: float

    def __call__(self, p: Points, rng: np.random.Generator) -> Points:
        if self.edge <= 0:
            return p
        xy = p.coord[:, :2]
        lo, hi = xy.min(0), xy.max(0)
        half = self.edge / 2
        # written as low + span * u so rounding can never make the span negative
        low = np.minimum(lo + half, (lo + hi) / 2)
        span = np.maximum(np.maximum(hi - half, (lo + hi) / 2) - low, 0.0)
        centre = low + span * np.array([rng.random(), rng.random()])
        return p.take(np.flatnonzero(np.all(np.abs(xy - centre) <= half, axis=1)))


@dataclass(frozen=True)
class Thin:
    """Keep each point with a probability drawn from ``[keep_min, keep_max]`` (density matching); fewer than
    ``min_points`` left gives back ``fallback`` (the scene before cropping)."""

    keep_min: float
    keep_max: float
    fallback: Points | None = None
    min_points: int = 10

    def __call__(self, p: Points, rng: np.random.Generator) -> Points:
        keep = rng.uniform(self.keep_min, max(self.keep_min, self.keep_max))
        out = p.take(np.flatnonzero(rng.random(len(p.rows)) < keep))
        if len(out.rows) < self.min_points and self.fallback is not None:  # a degenerate crop: the whole scene
            return self.fallback
        return out


@dataclass(frozen=True)
class Centre:
    """Move the mean to the origin (x and y only with ``xy_only``), then by a uniform offset up to ``offset`` m
    per axis (drawn only when ``offset`` is given)."""

    xy_only: bool = False
    offset: float | None = None

    def __call__(self, p: Points, rng: np.random.Generator) -> Points:
        xyz = p.coord.copy()
        if self.xy_only:
            xyz[:, :2] -= xyz[:, :2].mean(0)
        else:
            xyz = xyz - xyz.mean(0)
        if self.offset is not None:
            xyz = xyz + rng.uniform(-self.offset, self.offset, 3)
        return replace(p, coord=xyz)


@dataclass(frozen=True)
class Mirror:
    """Flip each of ``axes`` with probability 0.5."""

    axes: tuple[int, ...] = (0,)

    def __call__(self, p: Points, rng: np.random.Generator) -> Points:
        xyz = p.coord
        for axis in self.axes:
            if rng.random() < 0.5:
                xyz = xyz.copy() if xyz is p.coord else xyz
                xyz[:, axis] = -xyz[:, axis]
        return replace(p, coord=xyz)


@dataclass(frozen=True)
class Rotate:
    """Rotate by uniform angles up to ``max_x``, ``max_y``, ``max_z`` radians (``Rz @ Ry @ Rx``)."""

    max_x: float
    max_y: float
    max_z: float

    def __call__(self, p: Points, rng: np.random.Generator) -> Points:
        rot = rotation_matrix(rng.uniform(-self.max_x, self.max_x), rng.uniform(-self.max_y, self.max_y),
                              rng.uniform(-self.max_z, self.max_z))
        return replace(p, coord=p.coord @ rot.T)


@dataclass(frozen=True)
class Scale:
    """Scale by a uniform factor in ``1 +- amount``: one for all axes, or one per axis with ``per_axis``."""

    amount: float
    per_axis: bool = False

    def __call__(self, p: Points, rng: np.random.Generator) -> Points:
        f = rng.uniform(1 - self.amount, 1 + self.amount, 3) if self.per_axis else rng.uniform(1 - self.amount,
                                                                                                1 + self.amount)
        return replace(p, coord=p.coord * f)


@dataclass(frozen=True)
class ShiftZ:
    """Move up by a uniform amount in ``[low, high]`` m (floors neither flat nor at z = 0)."""

    low: float
    high: float

    def __call__(self, p: Points, rng: np.random.Generator) -> Points:
        xyz = p.coord.copy()
        xyz[:, 2] += rng.uniform(self.low, self.high)
        return replace(p, coord=xyz)


@dataclass(frozen=True)
class Jitter:
    """Gaussian noise on every coordinate, its sigma drawn uniformly in ``[low, high]`` m (sensor noise)."""

    low: float
    high: float

    def __call__(self, p: Points, rng: np.random.Generator) -> Points:
        return replace(p, coord=p.coord + rng.normal(0.0, rng.uniform(self.low, self.high), p.coord.shape))


@dataclass(frozen=True)
class Elastic:
    """Mask3D's elastic warp: with probability ``p``, each ``(granularity, magnitude)`` pair in turn."""

    pairs: tuple[tuple[float, float], ...]
    p: float
    warp: Callable[..., np.ndarray]

    def __call__(self, pts: Points, rng: np.random.Generator) -> Points:
        if not self.pairs or not rng.random() < self.p:
            return pts
        xyz = pts.coord
        for gran, mag in self.pairs:
            xyz = self.warp(xyz, gran, mag, rng=rng)
        return replace(pts, coord=xyz)


@dataclass(frozen=True)
class ColorDrop:
    """Grey the colours (each point's channel mean) with probability ``p``."""

    p: float

    def __call__(self, pts: Points, rng: np.random.Generator) -> Points:
        if self.p > 0 and rng.random() < self.p:
            return replace(pts, color=np.repeat(pts.color.mean(1, keepdims=True), 3, 1))
        return pts


@dataclass(frozen=True)
class ColorJitter:
    """Contrast about the mean colour, then brightness, both uniform in ``+- amount`` (brightness x 255)."""

    amount: float

    def __call__(self, pts: Points, rng: np.random.Generator) -> Points:
        if self.amount <= 0:
            return pts
        mean = pts.color.mean()
        color = (pts.color - mean) * (1 + rng.uniform(-self.amount, self.amount)) + mean
        color = color + rng.uniform(-self.amount, self.amount) * 255
        return replace(pts, color=color)


@dataclass(frozen=True)
class ColorShift:
    """Add a uniform offset in ``+- amount`` to each channel."""

    amount: float

    def __call__(self, pts: Points, rng: np.random.Generator) -> Points:
        if self.amount <= 0:
            return pts
        return replace(pts, color=pts.color + rng.uniform(-self.amount, self.amount, 3))
