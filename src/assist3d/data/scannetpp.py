"""ScanNet++ scans: ``data/<scene>/scans/`` mesh, segments, annotations and the ignore mask.

``scannetpp:PATH``: PATH is the dataset root holding ``data/``, or the ``data/`` folder itself, or
one scene folder. Per scene: ``scans/mesh_aligned_0.05.ply`` (vertex colours), ``segments.json``
(``segIndices``, one per vertex), ``segments_anno.json`` (``segGroups`` with ``segments`` and
``label``) and, optionally, ``mesh_aligned_0.05_mask.txt`` (vertex indices excluded from
evaluation -> ``valid = False``).

Objects (class-agnostic): every annotated group except the structural "stuff" labels in
:data:`STUFF_LABELS` (wall, floor, ceiling and their common spellings) and the annotation tool's
bookkeeping labels (``remove``, ``split``). ``segment`` is two-class: 0 = stuff, 1 = object,
-1 = unannotated.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from ..core.contracts import PointSample
from ..core import reading
from ..core.errors import DataError, shown
from .base import SceneDataset, instances_from_groups, integer_list, read_json, require_key
from .ply import read_scan_mesh

log = logging.getLogger(__name__)

MESH = "mesh_aligned_0.05.ply"
MASK = "mesh_aligned_0.05_mask.txt"
#: Labels (lower-cased, stripped) that are scene structure, not objects.
STUFF_LABELS: frozenset[str] = frozenset({
    "wall", "walls", "floor", "floors", "ceiling", "ceilings",
})
#: Annotation-tool labels that mark points to drop or re-split; treated as unannotated.
TOOL_LABELS: frozenset[str] = frozenset({"remove", "split", ""})


def _is_scene_dir(d: Path) -> bool:
    return (d / "scans" / MESH).is_file()


class ScanNetPPDataset(SceneDataset):
    """ScanNet++ (see the module docstring for layout and the object rule)."""

    def __init__(self, root: Path) -> None:
        root = Path(root)
        if not root.exists():
            raise DataError(f"{root}: ScanNet++ folder not found")
        if _is_scene_dir(root):
            dirs = {root.name: root}
        else:
            base = root / "data" if (root / "data").is_dir() else root
            dirs = {d.name: d for d in sorted(base.iterdir()) if d.is_dir() and _is_scene_dir(d)}
        self._scene_dir = dirs
        super().__init__(root, "scannetpp", list(dirs))

    def _load(self, scene_id: str) -> PointSample:
        scans = self._scene_dir[scene_id] / "scans"
        coord, color, normal = read_scan_mesh(scans / MESH)
        n = len(coord)

        seg_path = scans / "segments.json"
        seg = integer_list(seg_path, "segIndices", require_key(seg_path, read_json(seg_path), "segIndices", list))
        if seg.ndim != 1 or len(seg) != n:
            raise DataError(f"{seg_path}: {len(seg)} segment indices for a mesh of {n} vertices")
        anno_path = scans / "segments_anno.json"
        groups: list[tuple[list[int], bool, int]] = []
        for g in require_key(anno_path, read_json(anno_path), "segGroups", list):
            label = str(require_key(anno_path, g, "label", str)).strip().lower()
            segments = require_key(anno_path, g, "segments", list)
            if label in TOOL_LABELS:
                continue
            stuff = label in STUFF_LABELS
            groups.append((segments, not stuff, 0 if stuff else 1))
        instance, segment = instances_from_groups(anno_path, seg, groups)

        valid = np.ones(n, bool)
        mask_path = scans / MASK
        if mask_path.is_file():
            valid[_read_mask(mask_path, n)] = False
        return PointSample(
            scene_id=scene_id, coord=coord, color=color, normal=normal,
            instance=instance, segment=segment, valid=valid,
        )


def _read_mask(path: Path, n: int) -> np.ndarray:
    """Vertex indices listed one per line (blank file = nothing ignored)."""
    text = reading.read_bytes(path, limit=reading.MAX_TEXT_BYTES, what="ignore mask").split()
    try:
        idx = np.array(text, dtype=np.int64) if text else np.zeros(0, np.int64)
    except ValueError as e:
        raise DataError(f"{path}: ignore mask holds a non-integer entry ({shown(e)})") from None
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise DataError(f"{path}: ignore mask index out of range 0..{n - 1} (min {idx.min()}, max {idx.max()})")
    return idx
