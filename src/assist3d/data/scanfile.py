"""One scan file as a user has it: a ``.ply`` (mesh or point cloud) or an ``(N, 3|6|8)`` ``.npy``.

Unlike the dataset readers (``FORMAT:PATH``), raw points may hold non-finite coordinates: the caller
picks the ones to use (:func:`assist3d.learn.segmenter.predictor.usable_points`). An ``(N, 8)`` array is
read by the ``array`` reader and follows its rules (ground truth included).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.contracts import PointSample
from ..core.errors import DataError, shown
from .array import ArrayDataset
from .base import REAL_KINDS, SceneDataset, checked_coords, clean_colors, read_npy
from .ply import read_ply

#: suffixes :func:`read_scan` reads
SCAN_SUFFIXES = (".ply", ".npy")


@dataclass(frozen=True)
class ScanFile:
    """``coord`` (N, 3) float32 (may hold non-finite rows), ``color`` (N, 3) uint8 or None, and the
    ground truth as a :class:`PointSample` when the file carries it (an ``(N, 8)`` array), else None."""

    scene_id: str
    coord: np.ndarray
    color: np.ndarray | None
    sample: PointSample | None


def read_scan(path: str | Path) -> ScanFile:
    """Read one scan file with N > 0 points; one-line :class:`DataError` naming the file otherwise."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: input not found" + (" (it is a folder: give FORMAT:PATH)" if path.is_dir() else ""))
    suffix = path.suffix.lower()
    if suffix == ".ply":
        mesh = read_ply(path)
        coord, color = mesh.xyz(), mesh.rgb()
    elif suffix == ".npy":
        a = read_npy(path)
        if a.ndim != 2 or a.shape[1] not in (3, 6, 8) or a.dtype.kind not in REAL_KINDS:
            raise DataError(f"{path}: expected a numeric (N, 3), (N, 6) or (N, 8) array (xyz[, rgb[, semantic, instance]]), "
                            f"got {a.dtype} {a.shape}")
        if a.shape[1] == 8 and len(a):
            s = ArrayDataset(path).load(path.stem)
            return ScanFile(path.stem, s.coord, s.color, s)
        with np.errstate(over="ignore", invalid="ignore"):
            coord = np.ascontiguousarray(a[:, :3], np.float32)
        color = clean_colors(path, a[:, 3:6]) if a.shape[1] >= 6 else None
    else:
        raise DataError(f"{path}: unsupported input {suffix or '(no suffix)'}; give a .ply, an (N, 3|6|8) .npy or FORMAT:PATH")
    if len(coord) == 0:
        raise DataError(f"{path}: scene {shown(path.stem)} has no points")
    return ScanFile(path.stem, coord, color, None)


class ScanDataset(SceneDataset):
    """``scan:PATH``: scan files as a user has them (PATH one ``.ply`` or ``(N, 3|6|8)`` ``.npy``, or a folder
    of them; the scene id is the file stem), through :func:`read_scan`. Without ground truth (every file but
    an ``(N, 8)`` array) every point is background (instance -1), so such a scan can be segmented, viewed or
    measured but scores no object. As a dataset reader it keeps the readers' rules: non-finite or far-out
    coordinates are refused with one line naming the file (``assist3d segment FILE`` instead drops them)."""

    def __init__(self, root: Path) -> None:
        root = Path(root)
        if root.is_file():
            files = {root.stem: root}
        elif root.is_dir():
            files = {p.stem: p for p in sorted(root.iterdir()) if p.suffix.lower() in SCAN_SUFFIXES and p.is_file()}
        else:
            raise DataError(f"{root}: scan file or folder not found")
        if not files:
            raise DataError(f"{root}: no {' or '.join(SCAN_SUFFIXES)} scans in the folder")
        self._files = files
        super().__init__(root, "scan", list(files))

    def _load(self, scene_id: str) -> PointSample:
        path = self._files[scene_id]
        scan = read_scan(path)
        if scan.sample is not None:
            return scan.sample
        coord = checked_coords(path, scan.coord)
        n = len(coord)
        color = scan.color if scan.color is not None else np.zeros((n, 3), np.uint8)
        return PointSample(scene_id=scene_id, coord=coord, color=np.ascontiguousarray(color, np.uint8),
                           normal=np.zeros((n, 3), np.float32), instance=np.full(n, -1, np.int32),
                           segment=np.full(n, -1, np.int32), valid=np.ones(n, bool))
