"""The single-array scene format: one ``(N, 8) float32`` ``.npy`` per scene.

Columns: x, y, z, r, g, b, semantic (ScanNet-20 class index + 1; 0 = none), instance id.
``array:PATH``: PATH is one such file or a folder of them; the scene id is the file stem.

Objects follow the ScanNet protocol: points whose semantic label is 3..20 (the 18 classes other
than wall and floor) keep their instance id; labels 0, 1, 2 are void (instance -1). ``segment`` is
the ScanNet-20 index (semantic - 1; -1 for label 0). With ``array:PATH?objects=annotated`` every
annotated instance (id >= 1) counts except walls and floors (labels 1, 2): also the objects of
classes outside the 20 (label 0: lamps, boxes, pillows, ...), which arrangement statistics need
(the layout realism score) and the benchmark leaves out; a ceiling, which the ScanNet-20 labels
cannot name, counts too (``scannet:`` leaves it out; layout realism warns when an instance looks like
one). The default is ``objects=benchmark``.

Validation (``docs/evaluation.md``, "Input validation"): an array that is not ``(N, 8)`` real
numbers, has no rows, non-finite or far-out coordinates, fractional or non-finite labels, semantic
labels outside 0..20 or instance ids beyond int32 is refused; instance ids below -1 become void and
colours outside 0..255 are clipped, each with a warning.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from ..core.contracts import PointSample
from ..core.errors import DataError
from .base import (MAX_INSTANCE_ID, REAL_KINDS, SceneDataset, checked_coords, clean_colors, integer_labels, object_policy,
                   read_npy)

log = logging.getLogger(__name__)

FIRST_OBJECT_LABEL = 3
LAST_OBJECT_LABEL = 20


class ArrayDataset(SceneDataset):
    """Single-array ``.npy`` scenes (see the module docstring)."""

    def __init__(self, root: Path, *, objects: str = "benchmark") -> None:
        root = Path(root)
        self._annotated = object_policy(f"array:{root}", objects) == "annotated"
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
        if a.dtype.kind not in REAL_KINDS:
            raise DataError(f"{path}: expected a numeric array (int or float), got dtype {a.dtype}")
        coord = checked_coords(path, a[:, :3])
        n = len(a)
        semantic = integer_labels(path, a[:, 6], "semantic labels (column 6)", low=0, high=LAST_OBJECT_LABEL)
        inst = integer_labels(path, a[:, 7], "instance ids (column 7)", low=-1, high=MAX_INSTANCE_ID, void_below=True)
        if self._annotated:  # every annotated instance but walls and floors
            is_object = (inst >= 1) & ((semantic == 0) | (semantic >= FIRST_OBJECT_LABEL))
        else:
            is_object = (semantic >= FIRST_OBJECT_LABEL) & (semantic <= LAST_OBJECT_LABEL)
        return PointSample(
            scene_id=scene_id,
            coord=coord,
            color=clean_colors(path, a[:, 3:6]),
            normal=np.zeros((n, 3), np.float32),
            instance=np.where(is_object, inst, -1).astype(np.int32),
            segment=np.where(semantic > 0, semantic - 1, -1).astype(np.int32),
            valid=np.ones(n, bool),
        )
