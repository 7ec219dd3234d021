"""A generated dataset written as ScanNet v2 scans (``assist3d export scannet DATA OUT``).

``OUT/scans/<name>/`` per scene, ``<name>`` = ``scene%04d_%02d`` of (index mod 10000, index div
10000), so scene 7 is ``scene0007_00`` and scene 10007 ``scene0007_01`` (the name ScanNet's tools
parse with ``scene(\\d{4})_(\\d{2})``):

- ``<name>_vh_clean_2.ply``: binary PLY, vertex x y z (float), red green blue alpha (uchar), nx ny
  nz (float, our rendered normals) and one small triangle per point (the point and its two nearest
  neighbours, wound to face along the point's normal): our scenes are point sets, and the
  preprocessing scripts read ``face`` and derive normals from it;
- ``<name>_vh_clean_2.0.010000.segs.json``: ``segIndices``, the project's superpoints
  (:func:`assist3d.learn.segmenter.superpoints.superpoints`, ScanNet's graph segmentation on the
  point graph) split where they cross an object or surface boundary, so every object is a union
  of segments as in ScanNet;
- ``<name>.aggregation.json``: one segGroup per object (``label`` its ScanNet200 class name, see
  :mod:`assist3d.core.taxonomy.scannet`) and one each for the walls, the floor and the ceiling;
- ``<name>_vh_clean_2.labels.ply``: the same vertices and faces with a ``label`` (ushort NYU40 id);
- ``<name>.txt``: ``axisAlignment`` (identity) and ``sceneType`` lines.

Beside ``scans/``: ``scannetv2-labels.combined.tsv`` (ScanNet's label-map columns, one row per
label used: ``id`` the ScanNet200 id, ``nyu40id`` the NYU40 id of the label's ScanNet-20 class),
``Tasks/Benchmark/scannetv2_{train,val,test}.txt`` (the dataset's split rule; test empty), and
``export.json`` (the source dataset and which scene became which name).
"""

from __future__ import annotations

import csv
import io
import logging
from concurrent.futures import ProcessPoolExecutor
from contextlib import ExitStack
from multiprocessing import get_context
from pathlib import Path
from typing import Callable

import numpy as np

from ..core import reading
from ..core.errors import DataError
from ..core.fileio import write_bytes_atomic, write_json_atomic, write_text_atomic
from ..core.taxonomy.scannet import SURFACES, ScanNetLabel, scannet_label, surface_label
from ..data.ply import binary_ply, xyz_rgba_columns
from ..export.labels import surface_codes
from ..export.manifest import read_manifest, split_of
from ..export.ply import instance_palette
from ..export.writer import load_scene_arrays
from ..learn.segmenter.superpoints import superpoints

log = logging.getLogger(__name__)

__all__ = ["scannet_name", "export_scannet", "LABEL_MAP_NAME", "SPLIT_DIR", "MAX_EXPORT_INDEX"]

LABEL_MAP_NAME = "scannetv2-labels.combined.tsv"
SPLIT_DIR = Path("Tasks") / "Benchmark"
#: scene indices a ScanNet name can hold (4 digits of scene, 2 of scan)
MAX_EXPORT_INDEX = 100 * 10000 - 1
#: the columns of ScanNet's label map, in its order
TSV_COLUMNS = ("id", "raw_category", "category", "count", "nyu40id", "eigen13id", "nyuClass", "nyu40class",
               "eigen13class", "ModelNet40", "ModelNet10", "ShapeNetCore55", "synsetoffset", "wnsynsetid",
               "wnsynsetkey", "mpcat40", "mpcat40index")
SEGMENTS_PARAMS = {"kThresh": "0.01", "segMinVerts": "20", "source": "assist3d superpoints, split at labels"}


def scannet_name(index: int) -> str:
    """``scene%04d_%02d`` of scene index ``index`` (see the module docstring)."""
    if not 0 <= index <= MAX_EXPORT_INDEX:
        raise DataError(f"scene index {index}: a ScanNet name holds indices 0..{MAX_EXPORT_INDEX}")
    return f"scene{index % 10000:04d}_{index // 10000:02d}"


def _faces(coord: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(N, 3) int32: per point, a triangle with its two nearest neighbours facing along its normal."""
    from scipy.spatial import cKDTree  # heavy import, loaded only when exporting

    n = len(coord)
    if n < 3:
        raise DataError(f"a scene of {n} points cannot be written as a mesh (at least 3 are needed)")
    _, nn = cKDTree(coord).query(coord, 3)
    f = np.stack([np.arange(n), nn[:, 1], nn[:, 2]], axis=1).astype(np.int32)
    p = coord.astype(np.float64)
    fn = np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])
    flip = np.einsum("ij,ij->i", fn, normal.astype(np.float64)) < 0
    f[flip] = f[flip][:, [0, 2, 1]]
    return f


def _ply(coord: np.ndarray, rgb: np.ndarray, faces: np.ndarray, *, normal: np.ndarray | None = None,
         label: np.ndarray | None = None) -> bytes:
    cols = xyz_rgba_columns(coord, rgb)
    if normal is not None:
        cols += [("nx", "<f4", normal[:, 0]), ("ny", "<f4", normal[:, 1]), ("nz", "<f4", normal[:, 2])]
    if label is not None:
        cols.append(("label", "<u2", label))
    return binary_ply(cols, faces, comment="assist3d export, ScanNet v2 layout")


def finished_scenes(data: Path, out: Path) -> tuple[list[str], list[tuple[int, str]]]:
    """The class list and the finished scenes ``(index, id)``, in index order, of dataset ``data`` (its
    manifest), for an export into ``out``; one-line :class:`DataError` for a folder that is not a dataset,
    a damaged manifest, no finished scene, or an ``out`` inside the dataset."""
    fix = "; give a folder written by 'assist3d generate'"
    manifest = read_manifest(data, fix=fix)
    if manifest is None:
        raise DataError(f"{data}: not an assist3d dataset (no manifest.json){fix}")
    entries = manifest.get("scenes")
    classes = manifest.get("classes")
    if not isinstance(entries, list) or not isinstance(classes, list):
        raise DataError(f"{data / 'manifest.json'}: no 'scenes' or 'classes' list{fix}")
    todo: list[tuple[int, str]] = []
    for e in entries:
        if not (isinstance(e, dict) and isinstance(e.get("id"), str) and isinstance(e.get("index"), int)):
            raise DataError(f"{data / 'manifest.json'}: a scene entry lacks its 'id' or 'index'{fix}")
        todo.append((e["index"], e["id"]))
    if not todo:
        raise DataError(f"{data}: the dataset has no finished scene to export")
    if out.resolve() == data.resolve() or data.resolve() in out.resolve().parents:
        raise DataError(f"{out}: the export must not go inside the dataset folder {data}")
    return list(classes), sorted(todo)


def scene_with_room(data: Path, scene_id: str, classes: list[str]) -> dict:
    """A generated scene's arrays with its room height and class list (``layout.json``), for the exporters."""
    d = data / scene_id
    arrays = load_scene_arrays(d)
    layout = reading.read_json(d / "layout.json", what="layout")
    try:
        height = float(layout["room"]["height"])
        classes = list(layout.get("classes") or classes)
    except (ValueError, KeyError, TypeError, AttributeError) as e:
        raise DataError(f"{d / 'layout.json'}: unreadable room height ({type(e).__name__}: {e}); regenerate the scene") from None
    return {**arrays, "height": height, "classes": classes}


def _write_scene(scene: dict, folder: Path, name: str) -> tuple[int, dict[str, tuple[ScanNetLabel, int]]]:
    """Write one scan; returns its segment count and the labels it used (label -> (labels, groups))."""
    coord, color, normal = scene["coord"], scene["color"], scene["normal"]
    instance, segment, classes = scene["instance"], scene["segment"], scene["classes"]
    codes = surface_codes(coord, normal, instance, scene["height"])
    # the annotation unit of every point: an instance id, or -(surface code + 1) for the room
    unit = np.where(instance >= 0, instance.astype(np.int64), -(codes.astype(np.int64) + 1))
    sp = superpoints(coord)
    _, seg = np.unique(np.stack([sp, unit], axis=1), axis=0, return_inverse=True)
    seg = seg.reshape(-1).astype(np.int64)

    used: dict[str, tuple[ScanNetLabel, int]] = {}
    groups, nyu = [], np.zeros(len(coord), np.uint16)
    ids = np.unique(instance[instance >= 0])
    units: list[tuple[int, ScanNetLabel]] = []
    for inst in ids.tolist():
        m = instance == inst
        k = int(np.bincount(np.clip(segment[m], -1, None) + 1).argmax()) - 1  # the instance's class index
        units.append((inst, scannet_label(classes[k] if 0 <= k < len(classes) else "")))
    units += [(-(c + 1), surface_label(c)) for c in range(len(SURFACES)) if np.any(codes == c)]
    for k, (u, lab) in enumerate(units):
        m = unit == u
        groups.append({"id": k, "objectId": k, "segments": np.unique(seg[m]).tolist(), "label": lab.scannet200.name})
        nyu[m] = lab.nyu40id
        prev = used.get(lab.scannet200.name)
        used[lab.scannet200.name] = (lab, (prev[1] if prev else 0) + 1)

    faces = _faces(coord, normal)
    folder.mkdir(parents=True, exist_ok=True)
    write_bytes_atomic(folder / f"{name}_vh_clean_2.ply", _ply(coord, color, faces, normal=normal))
    write_bytes_atomic(folder / f"{name}_vh_clean_2.labels.ply",
                       _ply(coord, instance_palette(41)[nyu], faces, label=nyu))
    segs_file = f"{name}_vh_clean_2.0.010000.segs.json"
    write_json_atomic(folder / segs_file, {"params": SEGMENTS_PARAMS, "sceneId": name,
                                           "segIndices": seg.tolist()}, indent=None)
    write_json_atomic(folder / f"{name}.aggregation.json",
                      {"sceneId": f"scannet.{name}", "appId": "assist3d", "segGroups": groups,
                       "segmentsFile": f"scannet.{segs_file}"}, indent=None)
    write_text_atomic(folder / f"{name}.txt", "axisAlignment = 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n"
                      "sceneType = Misc.\n")
    return int(seg.max()) + 1, used


def _label_map(used: dict[str, tuple[ScanNetLabel, int]]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, delimiter="\t", lineterminator="\n")
    w.writerow(TSV_COLUMNS)
    for name, (lab, count) in sorted(used.items(), key=lambda kv: kv[1][0].scannet200.id):
        nyu_class = lab.name20 if lab.index20 >= 0 else lab.scannet200.nyu40class
        row = {"id": lab.scannet200.id, "raw_category": name, "category": name, "count": count,
               "nyu40id": lab.nyu40id, "nyu40class": nyu_class}
        w.writerow([row.get(c, "") for c in TSV_COLUMNS])
    return buf.getvalue()


def _export_one(job: tuple[Path, str, list[str], Path, str]) -> tuple[str, dict[str, tuple[ScanNetLabel, int]]]:
    data, scene_id, classes, out, name = job
    _, used = _write_scene(scene_with_room(data, scene_id, classes), out / "scans" / name, name)
    return name, used


def export_scannet(data: str | Path, out: str | Path, *, workers: int = 1,
                   on_scene: Callable[[str, str], None] | None = None) -> dict:
    """Write every finished scene of dataset ``data`` as a ScanNet scan under ``out`` (see the module
    docstring), ``workers`` scenes at a time (processes; the files do not depend on it).
    ``on_scene(scene_id, name)`` is called after each. Returns a summary (``scenes``, ``splits``,
    ``labels``, ``out``)."""
    data, out = Path(data), Path(out)
    classes, todo = finished_scenes(data, out)
    names: dict[str, str] = {}
    splits: dict[str, list[str]] = {"train": [], "val": [], "test": []}
    used: dict[str, tuple[ScanNetLabel, int]] = {}
    jobs = [(data, scene_id, classes, out, scannet_name(index)) for index, scene_id in sorted(todo)]
    with ExitStack() as stack:
        if workers > 1 and len(jobs) > 1:
            pool = stack.enter_context(ProcessPoolExecutor(min(workers, len(jobs)), mp_context=get_context("spawn")))
            results = pool.map(_export_one, jobs)
        else:
            results = map(_export_one, jobs)
        for (index, scene_id), (name, scene_used) in zip(sorted(todo), results):
            for label, (lab, n) in scene_used.items():
                used[label] = (lab, used.get(label, (lab, 0))[1] + n)
            names[name] = scene_id
            splits[split_of(index)].append(name)
            if on_scene is not None:
                on_scene(scene_id, name)
    write_text_atomic(out / LABEL_MAP_NAME, _label_map(used))
    for split, listed in splits.items():
        write_text_atomic(out / SPLIT_DIR / f"scannetv2_{split}.txt", "".join(f"{s}\n" for s in listed))
    summary = {"format": "assist3d-scannet-export", "version": 1, "source": str(data), "scenes": names,
               "splits": {k: len(v) for k, v in splits.items()}, "labels": len(used)}
    write_json_atomic(out / "export.json", summary)
    return {**summary, "out": str(out), "scenes": len(names)}
