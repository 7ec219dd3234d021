"""Small synthetic scenes for tests, the model benchmark and the CPU fit when no generated data exists.

A scene is a floor (background, instance -1) with walls on two sides and ``num_objects`` axis-aligned
boxes of random size, colour and yaw standing on it; points are sampled uniformly on the visible box
surfaces (top and four sides). Written in the Pointcept layout so any reader of that layout loads it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ...core.contracts import PointSample
from ...export.writer import META_NAME
from ...core.fileio import write_npy_atomic, write_text_atomic


def _sample_rect(rng: np.random.Generator, n: int, origin: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    a = rng.random((n, 1))
    b = rng.random((n, 1))
    return origin + a * u + b * v


def make_toy_scene(scene_id: str, *, rng: np.random.Generator, num_objects: int = 6, room_m: float = 5.0,
                   density_per_m2: float = 2500.0) -> PointSample:
    """One scene: ``room_m`` x ``room_m`` floor, two walls and ``num_objects`` boxes (instance ids 0..)."""
    parts_xyz, parts_col, parts_inst = [], [], []

    def add(xyz: np.ndarray, color: np.ndarray, inst: int) -> None:
        jitter = rng.integers(-12, 13, (len(xyz), 3))
        parts_xyz.append(xyz)
        parts_col.append(np.clip(color[None, :] + jitter, 0, 255))
        parts_inst.append(np.full(len(xyz), inst, np.int32))

    area = room_m * room_m
    add(_sample_rect(rng, int(area * density_per_m2), np.zeros(3), np.array([room_m, 0, 0]),
                     np.array([0, room_m, 0])), np.array([150, 140, 120]), -1)
    h = 2.6
    add(_sample_rect(rng, int(room_m * h * density_per_m2), np.array([0, room_m, 0]), np.array([room_m, 0, 0]),
                     np.array([0, 0, h])), np.array([220, 220, 210]), -1)
    add(_sample_rect(rng, int(room_m * h * density_per_m2), np.zeros(3), np.array([0, room_m, 0]),
                     np.array([0, 0, h])), np.array([210, 215, 220]), -1)
    placed: list[tuple[float, float, float]] = []
    inst = 0
    for _ in range(num_objects * 20):
        if inst >= num_objects:
            break
        w, d = rng.uniform(0.4, 1.4, 2)
        hgt = rng.uniform(0.3, 1.5)
        r = 0.5 * float(np.hypot(w, d))
        cx, cy = rng.uniform(r + 0.05, room_m - r - 0.05, 2)
        if any(np.hypot(cx - px, cy - py) < r + pr + 0.1 for px, py, pr in placed):
            continue
        placed.append((cx, cy, r))
        yaw = rng.uniform(0, np.pi)
        rot = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
        ex, ey, ez = rot @ np.array([w, 0, 0]), rot @ np.array([0, d, 0]), np.array([0, 0, hgt])
        corner = np.array([cx, cy, 0.0]) - 0.5 * ex - 0.5 * ey
        color = rng.integers(30, 226, 3).astype(np.int64)
        faces = [(corner + ez, ex, ey), (corner, ex, ez), (corner + ey, ex, ez), (corner, ey, ez),
                 (corner + ex, ey, ez)]
        for origin, u, v in faces:
            n = max(int(np.linalg.norm(np.cross(u, v)) * density_per_m2), 10)
            add(_sample_rect(rng, n, origin, u, v), color, inst)
        inst += 1
    coord = np.concatenate(parts_xyz).astype(np.float32)
    n = len(coord)
    instance = np.concatenate(parts_inst)
    return PointSample(scene_id=scene_id, coord=coord, color=np.concatenate(parts_col).astype(np.uint8),
                       normal=np.zeros((n, 3), np.float32), instance=instance,
                       segment=np.where(instance >= 0, 0, -1).astype(np.int32), valid=np.ones(n, bool))


def write_pointcept_scene(folder: Path, sample: PointSample) -> None:
    """Write ``sample`` as a Pointcept scene folder (coord/color/normal/segment/instance .npy + meta.json)."""
    folder.mkdir(parents=True, exist_ok=True)
    write_npy_atomic(folder / "coord.npy", sample.coord)
    write_npy_atomic(folder / "color.npy", sample.color)
    write_npy_atomic(folder / "normal.npy", sample.normal)
    write_npy_atomic(folder / "segment.npy", sample.segment)
    write_npy_atomic(folder / "instance.npy", sample.instance)
    meta = {"scene_id": sample.scene_id, "points": len(sample), "instances": int(sample.instance.max()) + 1,
            "source": "assist3d.learn.engine.toy"}
    write_text_atomic(folder / META_NAME, json.dumps(meta, indent=1) + "\n")


def write_toy_dataset(out: str | Path, num_scenes: int, *, seed: int, num_objects: int = 6, room_m: float = 5.0,
                      density_per_m2: float = 2500.0) -> list[Path]:
    """``num_scenes`` toy scenes under ``out/scene_NNNN`` in the Pointcept layout; seeds per (seed, index)."""
    out = Path(out)
    folders = []
    for i in range(num_scenes):
        rng = np.random.default_rng(np.random.SeedSequence([seed, i]))
        sample = make_toy_scene(f"scene_{i:04d}", rng=rng, num_objects=num_objects, room_m=room_m,
                                density_per_m2=density_per_m2)
        folder = out / sample.scene_id
        write_pointcept_scene(folder, sample)
        folders.append(folder)
    return folders
