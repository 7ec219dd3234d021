"""ScanNet v2 raw scans: mesh PLY + over-segmentation + aggregation + the label map.

Layout (``scannet:PATH``): PATH holds scene folders (or a ``scans/`` folder holding them, or is one
scene folder), each with ``<scene>_vh_clean_2.ply``, ``<scene>_vh_clean_2.0.010000.segs.json`` and
``<scene>.aggregation.json``. The label map ``scannetv2-labels.combined.tsv`` is taken from
``?labels=FILE`` when given, else from PATH, its parent or its grandparent (the layouts of the
official download), else from each scene folder.

Objects are the instances of the 18 ScanNet benchmark classes (nyu40 ids below); every other point
(walls, floors, other classes, unannotated vertices) has instance -1. With
``scannet:PATH?objects=annotated`` every annotated instance whose label the map knows counts, except
structure (nyu40 wall 1, floor 2, ceiling 22): what arrangement statistics need (the layout realism
score), where the benchmark keeps its 18 classes. ``segment`` is the ScanNet-20
class index (0 wall, 1 floor, 2 cabinet, ...), -1 outside the 20 classes. Points are in mesh-vertex
order; normals are the mesh's area-weighted vertex normals.
"""

from __future__ import annotations

import csv
import io
import logging
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..core.contracts import PointSample
from ..core import reading
from ..core.errors import DataError, shown
from .base import SceneDataset, instances_from_groups, integer_list, object_policy, read_json, require_key
from .ply import read_scan_mesh

log = logging.getLogger(__name__)

LABEL_MAP_NAME = "scannetv2-labels.combined.tsv"
#: nyu40 ids of the 20 ScanNet benchmark semantic classes (index = ScanNet-20 class index).
SCANNET20_NYU40: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 14, 16, 24, 28, 33, 34, 36, 39)
#: nyu40 ids of the 18 instance classes (the 20 without wall 1 and floor 2).
SCANNET18_NYU40: tuple[int, ...] = SCANNET20_NYU40[2:]
#: nyu40 ids of the room's structure (wall, floor, ceiling): never objects.
STRUCTURE_NYU40: tuple[int, ...] = (1, 2, 22)


@lru_cache(maxsize=8)
def read_label_map(path: Path) -> dict[str, int]:
    """``raw_category -> nyu40id`` from ``scannetv2-labels.combined.tsv``."""
    text = reading.read_text(path, what="label map")
    try:
        rows = list(csv.reader(io.StringIO(text, newline=""), delimiter="\t"))
    except csv.Error as e:
        raise DataError(f"{shown(path, 400)}: malformed label map ({shown(e)})") from None
    if not rows:
        raise DataError(f"{path}: empty label map")
    header = rows[0]
    if "raw_category" not in header or "nyu40id" not in header:
        raise DataError(f"{path}: label map header lacks 'raw_category' or 'nyu40id' columns (has {shown(header[:6])})")
    ci, ni = header.index("raw_category"), header.index("nyu40id")
    out: dict[str, int] = {}
    for line_no, row in enumerate(rows[1:], start=2):
        if len(row) <= max(ci, ni) or not row[ni].strip():
            continue
        try:
            out[row[ci]] = int(row[ni])
        except ValueError:
            raise DataError(f"{path}: line {line_no}: nyu40id '{shown(row[ni])}' is not an integer") from None
    return out


def _find_label_map(root: Path, labels: str | None) -> Path | None:
    if labels:
        p = Path(labels).expanduser()
        if not p.is_file():
            raise DataError(f"{p}: label map given with ?labels= not found")
        return p
    for d in (root, root.parent, root.parent.parent):
        if (d / LABEL_MAP_NAME).is_file():
            return d / LABEL_MAP_NAME
    return None


def _object_id(path: Path, group: object) -> int:
    """A segGroup's ``objectId`` (else ``id``, else 0), the order objects are numbered in."""
    if not isinstance(group, dict):
        return 0  # reported as a missing key when the group is read
    value = group.get("objectId", group.get("id", 0))
    if isinstance(value, bool) or not isinstance(value, int):
        raise DataError(f"{path}: segGroups objectId '{shown(value, 40)}' is not an integer")
    return value


def _is_scene_dir(d: Path) -> bool:
    return (d / f"{d.name}_vh_clean_2.ply").is_file()


class ScanNetDataset(SceneDataset):
    """ScanNet v2 raw scans (see the module docstring for layout and labels)."""

    def __init__(self, root: Path, *, labels: str | None = None, objects: str = "benchmark") -> None:
        root = Path(root)
        self._annotated = object_policy(f"scannet:{root}", objects) == "annotated"
        if not root.exists():
            raise DataError(f"{root}: ScanNet folder not found")
        if _is_scene_dir(root):
            self._scene_dir = {root.name: root}
        else:
            base = root / "scans" if (root / "scans").is_dir() else root
            self._scene_dir = {d.name: d for d in sorted(base.iterdir()) if d.is_dir() and _is_scene_dir(d)}
        self._labels_path = _find_label_map(root, labels)
        super().__init__(root, "scannet", list(self._scene_dir))

    def _label_map(self, scene_dir: Path) -> dict[str, int]:
        path = self._labels_path
        if path is None and (scene_dir / LABEL_MAP_NAME).is_file():
            path = scene_dir / LABEL_MAP_NAME
        if path is None:
            raise DataError(
                f"{self.root}: {LABEL_MAP_NAME} not found in the folder, its parent or grandparent; "
                f"give it as 'scannet:{self.root}?labels=/path/to/{LABEL_MAP_NAME}'"
            )
        return read_label_map(path)

    def _load(self, scene_id: str) -> PointSample:
        d = self._scene_dir[scene_id]
        coord, color, normal = read_scan_mesh(d / f"{scene_id}_vh_clean_2.ply")
        n = len(coord)

        segs_path = d / f"{scene_id}_vh_clean_2.0.010000.segs.json"
        seg = integer_list(segs_path, "segIndices", require_key(segs_path, read_json(segs_path), "segIndices", list))
        if seg.ndim != 1 or len(seg) != n:
            raise DataError(f"{segs_path}: {len(seg)} segment indices for a mesh of {n} vertices")

        agg_path = d / f"{scene_id}.aggregation.json"
        groups_raw = require_key(agg_path, read_json(agg_path), "segGroups", list)
        label_map = self._label_map(d)
        nyu_to_20 = {nyu: i for i, nyu in enumerate(SCANNET20_NYU40)}
        groups: list[tuple[list[int], bool, int]] = []
        unknown: set[str] = set()
        for g in sorted(groups_raw, key=lambda g: _object_id(agg_path, g)):
            label = require_key(agg_path, g, "label", str)
            segments = require_key(agg_path, g, "segments", list)
            nyu = label_map.get(label)
            if nyu is None:
                unknown.add(label)
                nyu = 0
            is_object = nyu in SCANNET18_NYU40 or (self._annotated and nyu > 0 and nyu not in STRUCTURE_NYU40)
            groups.append((segments, is_object, nyu_to_20.get(nyu, -1)))
        if unknown:
            log.warning("%s: labels not in the label map (treated as void): %s", agg_path, shown(sorted(unknown), 400))
        instance, segment = instances_from_groups(agg_path, seg, groups)
        return PointSample(
            scene_id=scene_id, coord=coord, color=color, normal=normal,
            instance=instance, segment=segment, valid=np.ones(n, bool),
        )
