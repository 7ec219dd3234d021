"""Binary PLY export of a labelled point cloud, coloured by instance for viewing in any tool."""

from __future__ import annotations

import colorsys
import io
from pathlib import Path

import numpy as np

from ..core.contracts import PointSample
from ..core.fileio import write_bytes_atomic

__all__ = ["instance_palette", "instance_colors", "ply_bytes", "write_ply"]

BACKGROUND_RGB = (170, 170, 170)


def instance_palette(count: int) -> np.ndarray:
    """(count, 3) uint8 well-separated colours (golden-ratio hue steps, varied value)."""
    cols = []
    for i in range(count):
        h = (i * 0.618033988749895) % 1.0
        s = 0.65 + 0.3 * ((i * 7) % 3) / 2
        v = 0.95 - 0.25 * ((i * 5) % 2)
        cols.append([round(255 * c) for c in colorsys.hsv_to_rgb(h, s, v)])
    return np.asarray(cols, dtype=np.uint8).reshape(-1, 3)


def instance_colors(instance: np.ndarray) -> np.ndarray:
    """(N, 3) uint8 colour per point: a palette colour per instance id, grey for -1."""
    instance = np.asarray(instance)
    out = np.zeros((len(instance), 3), np.uint8)
    out[:] = BACKGROUND_RGB
    obj = instance >= 0
    if obj.any():
        pal = instance_palette(int(instance.max()) + 1)
        out[obj] = pal[instance[obj]]
    return out


def ply_bytes(sample: PointSample, *, color_by: str = "instance") -> bytes:
    """A binary little-endian PLY with x y z (float32), red green blue (uint8), instance and
    segment (int32). ``color_by`` is ``instance`` or ``rgb``."""
    n = len(sample)
    rgb = instance_colors(sample.instance) if color_by == "instance" else sample.color
    rec = np.zeros(n, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"),
                             ("blue", "u1"), ("instance", "<i4"), ("segment", "<i4")])
    rec["x"], rec["y"], rec["z"] = sample.coord[:, 0], sample.coord[:, 1], sample.coord[:, 2]
    rec["red"], rec["green"], rec["blue"] = rgb[:, 0], rgb[:, 1], rgb[:, 2]
    rec["instance"], rec["segment"] = sample.instance, sample.segment
    header = ("ply\nformat binary_little_endian 1.0\ncomment assist3d point cloud coloured by " + color_by + "\n"
              f"element vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\n"
              "property int instance\nproperty int segment\nend_header\n")
    buf = io.BytesIO()
    buf.write(header.encode("ascii"))
    buf.write(rec.tobytes())
    return buf.getvalue()


def write_ply(path: str | Path, sample: PointSample, *, color_by: str = "instance") -> None:
    """Write :func:`ply_bytes` atomically."""
    write_bytes_atomic(path, ply_bytes(sample, color_by=color_by))
