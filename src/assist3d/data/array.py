"""The single-array scene format: one ``(N, 8) float32`` ``.npy`` per scene.

Columns: x, y, z, r, g, b, semantic (ScanNet-20 class index + 1; 0 = none), instance id.
``array:PATH``: PATH is one such file or a folder of them; the scene id is the file stem.

Objects follow the ScanNet protocol: points whose semantic label is 3..20 (the 18 classes other
than wall and floor) keep their instance id; labels 0, 1, 2 are void (instance -1). ``segment`` is
the ScanNet-20 index (semantic - 1; -1 for label 0).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from ..contracts import PointSample
from ..errors import DataError
from .base import SceneDataset, read_npy

log = logging.getLogger(__name__)

FIRST_OBJECT_LABEL = 3
LAST_OBJECT_LABEL = 20


class ArrayDataset(SceneDataset):
    """Single-array ``.npy`` scenes (see the module docstring)."""

    def __init__(self, root: Path) -> None:
        root = Path(root)
        if root.is_file():
            files = {root.stem: root}
        elif root.is_dir():
            files = {p.stem: p for p in sorted(root.glob("*.npy")) if p.is_file()}
        else:
            raise DataError(f"{root}: array file or folder not found")
        self._files = files
        super().__init__(root, "array", list(files))

    def _load(self, scene_id: str) -> PointSample:
        path = self._files[scene_id]
        a = read_npy(path)
        if a.ndim != 2 or a.shape[1] != 8:
            raise DataError(f"{path}: expected an (N, 8) array (xyz, rgb, semantic, instance), got shape {a.shape}")
        if not np.issubdtype(a.dtype, np.number):
            raise DataError(f"{path}: expected a numeric array, got dtype {a.dtype}")
        n = len(a)
        semantic = np.rint(a[:, 6]).astype(np.int32)
        inst = np.rint(a[:, 7]).astype(np.int32)
        is_object = (semantic >= FIRST_OBJECT_LABEL) & (semantic <= LAST_OBJECT_LABEL)
        return PointSample(
            scene_id=scene_id,
            coord=np.ascontiguousarray(a[:, :3], dtype=np.float32),
            color=np.clip(np.rint(a[:, 3:6]), 0, 255).astype(np.uint8),
            normal=np.zeros((n, 3), np.float32),
            instance=np.where(is_object, inst, -1).astype(np.int32),
            segment=np.where(semantic > 0, semantic - 1, -1).astype(np.int32),
            valid=np.ones(n, bool),
        )
