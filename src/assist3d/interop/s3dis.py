"""A generated dataset written as S3DIS rooms (``assist3d export s3dis DATA OUT``).

``OUT/Area_1/<scene_id>/Annotations/<class>_<k>.txt`` for the training scenes and ``OUT/Area_5/...``
for the validation scenes (S3DIS's usual test area; the dataset's split rule), one file per object
and one each for the walls, the floor and the ceiling, one point per line ``x y z r g b``
(coordinates in metres to 0.1 mm, colours 0-255), and ``OUT/Area_N/Area_N_alignmentAngle.txt``
listing the rooms (angle 0), what Pointcept's S3DIS preprocessing reads.

Classes are S3DIS's 13: the room's surfaces are ceiling, floor and wall; an object is table, chair,
sofa, bookcase, door, window or board where its ScanNet class says so (desk counts as table), every
other object is clutter.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Callable

import numpy as np

from ..core.fileio import write_bytes_atomic, write_text_atomic
from ..core.taxonomy.scannet import SURFACES, scannet_label
from ..export.labels import surface_codes
from ..export.manifest import split_of
from .scannet import finished_scenes, scene_with_room

__all__ = ["export_s3dis", "s3dis_class", "AREAS"]

#: split -> the S3DIS area its scenes go to
AREAS = {"train": "Area_1", "val": "Area_5"}
_FROM_SCANNET20 = {"chair": "chair", "table": "table", "desk": "table", "sofa": "sofa", "bookshelf": "bookcase",
                   "door": "door", "window": "window"}
_BOARDS = frozenset({"whiteboard", "blackboard", "bulletin board", "board"})


def s3dis_class(class_name: str) -> str:
    """The S3DIS class of one of our object classes (see the module docstring)."""
    lab = scannet_label(class_name)
    if lab.scannet200.name in _BOARDS:
        return "board"
    return _FROM_SCANNET20.get(lab.name20, "clutter")


def _txt(coord: np.ndarray, color: np.ndarray) -> bytes:
    buf = io.StringIO()
    rows = np.column_stack([np.round(coord.astype(np.float64), 4), color.astype(np.int64)])
    np.savetxt(buf, rows, fmt=["%.4f", "%.4f", "%.4f", "%d", "%d", "%d"])
    return buf.getvalue().encode("ascii")


def export_s3dis(data: str | Path, out: str | Path, *, on_scene: Callable[[str, str], None] | None = None) -> dict:
    """Write every finished scene of dataset ``data`` as an S3DIS room under ``out``. Returns a summary."""
    data, out = Path(data), Path(out)
    classes, todo = finished_scenes(data, out)
    rooms: dict[str, list[str]] = {a: [] for a in AREAS.values()}
    for index, sid in todo:
        a = scene_with_room(data, sid, classes)
        height, names = a["height"], a["classes"]
        area = AREAS[split_of(index)]
        anno = out / area / sid / "Annotations"
        anno.mkdir(parents=True, exist_ok=True)
        for old in anno.glob("*.txt"):  # a re-export replaces the room's files
            old.unlink()
        counts: dict[str, int] = {}
        codes = surface_codes(a["coord"], a["normal"], a["instance"], height)
        groups: list[tuple[str, np.ndarray]] = []
        for inst in np.unique(a["instance"][a["instance"] >= 0]).tolist():
            m = a["instance"] == inst
            k = int(np.bincount(np.clip(a["segment"][m], -1, None) + 1).argmax()) - 1
            groups.append((s3dis_class(names[k] if 0 <= k < len(names) else ""), m))
        groups += [(SURFACES[c], codes == c) for c in range(len(SURFACES)) if np.any(codes == c)]
        for cls, m in groups:
            counts[cls] = counts.get(cls, 0) + 1
            write_bytes_atomic(anno / f"{cls}_{counts[cls]}.txt", _txt(a["coord"][m], a["color"][m]))
        rooms[area].append(sid)
        if on_scene is not None:
            on_scene(sid, str(out / area / sid))
    for area, listed in rooms.items():
        if listed:
            write_text_atomic(out / area / f"{area}_alignmentAngle.txt",
                              f"## Global alignment angle per disjoint space in {area} ##\n"
                              + "".join(f"{r} 0\n" for r in listed))
    return {"format": "assist3d-s3dis-export", "out": str(out), "scenes": sum(map(len, rooms.values())),
            "areas": {k: len(v) for k, v in rooms.items()}}
