"""Scene folders in the Pointcept layout, with a completion marker written last.

``DIR/<scene_id>/`` holds ``coord.npy`` (N, 3) float32, ``color.npy`` (N, 3) uint8,
``normal.npy`` (N, 3) float32, ``instance.npy`` (N,) int32 (-1 = background), ``segment.npy``
(N,) int32 (class index, -1 = background), ``segment20.npy`` and ``segment200.npy`` (N,) int32
(the ScanNet-20 / ScanNet200 class, the room's wall, floor and ceiling included; :mod:`.labels`),
``layout.json``, optionally ``points.ply`` and ``scene.glb``, and last ``meta.json`` with the
seed, counts, timings and a hash of every file.
A folder without a valid ``meta.json`` is incomplete and is regenerated on resume.
"""

from __future__ import annotations

import hashlib
import io
import json
import logging
import time
from pathlib import Path
from typing import Callable

import numpy as np

from ..core.contracts import PointSample, SceneLayout
from ..core import reading
from ..core.errors import DataError, shown
from ..core.fileio import write_bytes_atomic, write_json_atomic
from ..core.paths import inside
from .labels import scannet_segments
from .ply import ply_bytes

log = logging.getLogger(__name__)

__all__ = ["ARRAYS", "META_NAME", "write_scene", "read_scene_meta", "load_scene_arrays", "file_digest",
           "remove_stale_temps", "scene_sample", "export_scene_ply"]

ARRAYS: dict[str, tuple[str, int]] = {  # name -> (dtype, columns; 0 = 1-d)
    "coord": ("float32", 3),
    "color": ("uint8", 3),
    "normal": ("float32", 3),
    "instance": ("int32", 0),
    "segment": ("int32", 0),
}
META_NAME = "meta.json"
MARKER_FORMAT = "assist3d-scene"


def file_digest(data: bytes) -> str:
    """blake2b-128 hex digest of file contents."""
    return hashlib.blake2b(data, digest_size=16).hexdigest()


def _npy_bytes(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, np.ascontiguousarray(a), allow_pickle=False)
    return buf.getvalue()


def write_scene(scene_dir: str | Path, sample: PointSample, layout: SceneLayout, meta: dict, *,
                ply: bool = False, glb_writer: Callable[[Path], None] | None = None) -> dict:
    """Write one scene folder atomically, file by file, and ``meta.json`` last.

    ``meta`` is merged into the marker (seed, timings, ...); the marker also records every file's
    size and digest, and, when ``meta["seconds"]`` is a dict, the time spent writing as its
    ``"write"`` entry. ``glb_writer(path)`` writes the assembled mesh when given. Returns the marker.
    """
    t0 = time.perf_counter()
    d = Path(scene_dir)
    d.mkdir(parents=True, exist_ok=True)
    (d / META_NAME).unlink(missing_ok=True)  # the folder is incomplete until the marker is back
    remove_stale_temps(d)
    files: dict[str, dict] = {}

    def put(name: str, data: bytes) -> None:
        write_bytes_atomic(d / name, data)
        files[name] = {"bytes": len(data), "blake2b": file_digest(data)}

    arrays = {"coord": sample.coord, "color": sample.color, "normal": sample.normal,
              "instance": sample.instance, "segment": sample.segment}
    for name, a in arrays.items():
        put(f"{name}.npy", _npy_bytes(a))
    seg20, seg200 = scannet_segments(sample.coord, sample.normal, sample.instance, sample.segment, layout.classes,
                                     layout.room.height)
    put("segment20.npy", _npy_bytes(seg20))
    put("segment200.npy", _npy_bytes(seg200))
    put("layout.json", (json.dumps(layout.to_json(), indent=1) + "\n").encode("utf-8"))
    if ply:
        put("points.ply", ply_bytes(sample))
    else:
        (d / "points.ply").unlink(missing_ok=True)
    if glb_writer is not None:
        glb_writer(d / "scene.glb")
        data = (d / "scene.glb").read_bytes()
        files["scene.glb"] = {"bytes": len(data), "blake2b": file_digest(data)}
    marker = {"format": MARKER_FORMAT, "version": 1, **meta, "points": len(sample), "files": files}
    if isinstance(marker.get("seconds"), dict):
        marker["seconds"] = {**marker["seconds"], "write": round(time.perf_counter() - t0, 4)}
    write_json_atomic(d / META_NAME, marker)
    return marker


def remove_stale_temps(folder: str | Path) -> int:
    """Delete temporary files a killed writer left in ``folder`` (``.<name>.<random>.tmp``, the
    pattern of :func:`assist3d.core.fileio.atomic_path`); returns how many."""
    n = 0
    for p in Path(folder).glob(".*.tmp"):
        p.unlink(missing_ok=True)
        n += 1
    return n


def read_scene_meta(scene_dir: str | Path, *, check_files: bool = True) -> dict | None:
    """The completion marker of a scene folder, or None if the scene is absent or incomplete
    (no marker, unreadable marker, or a listed file missing or changed)."""
    d = Path(scene_dir)
    if not (d / META_NAME).exists():
        return None
    try:
        meta = reading.read_json(d / META_NAME)
    except DataError:
        return None
    if not isinstance(meta, dict) or meta.get("format") != MARKER_FORMAT or not isinstance(meta.get("files"), dict):
        return None
    if check_files:
        for name, info in meta["files"].items():
            try:
                p = inside(d, name, what=f"{d / META_NAME}: files")  # a listed file outside the folder: tampered
                if p.stat().st_size != info["bytes"] or file_digest(p.read_bytes()) != info["blake2b"]:
                    return None
            except (OSError, KeyError, TypeError, DataError):
                return None
    return meta


def load_scene_arrays(scene_dir: str | Path) -> dict[str, np.ndarray]:
    """Load a scene folder's arrays (no pickles, headers checked) and check dtypes and shapes."""
    d = Path(scene_dir)
    out: dict[str, np.ndarray] = {}
    for name, (dtype, cols) in ARRAYS.items():
        p = d / f"{name}.npy"
        if not p.exists():
            raise DataError(f"{shown(p, 400)}: missing; regenerate the scene")
        try:
            a = reading.read_npy(p)
        except DataError as e:
            raise DataError(f"{shown(p, 400)}: unreadable ({reading.problem(e, p)}); regenerate the scene") from None
        if a.dtype != np.dtype(dtype) or (cols and (a.ndim != 2 or a.shape[1] != cols)) or (not cols and a.ndim != 1):
            raise DataError(f"{p}: expected {dtype} {'(N, %d)' % cols if cols else '(N,)'}, got {a.dtype} {a.shape}")
        out[name] = a
    n = {len(a) for a in out.values()}
    if len(n) != 1:
        raise DataError(f"{d}: arrays disagree on the point count: { {k: len(v) for k, v in out.items()} }")
    return out


def scene_sample(scene_dir: str | Path) -> PointSample:
    """A scene folder's arrays as a :class:`PointSample` (every point valid), checked like
    :func:`load_scene_arrays`."""
    d = Path(scene_dir)
    a = load_scene_arrays(d)
    return PointSample(d.name, a["coord"], a["color"], a["normal"], a["instance"], a["segment"],
                       np.ones(len(a["coord"]), bool))


def export_scene_ply(scene_dir: str | Path) -> bool:
    """Write a finished scene's ``points.ply`` from its arrays (the bytes ``generate --ply`` writes) and
    list it in the scene's ``meta.json``; False, writing nothing, when the marker lists it already.
    A scene without a valid marker (unfinished or changed) is refused with a :class:`DataError`."""
    d = Path(scene_dir)
    meta = read_scene_meta(d)
    if meta is None:
        raise DataError(f"{d}: not a finished scene (no valid {META_NAME}, or a file it lists is missing or "
                        "changed); re-run `assist3d generate` to complete it")
    if "points.ply" in meta["files"]:
        return False
    data = ply_bytes(scene_sample(d))
    write_bytes_atomic(d / "points.ply", data)
    meta["files"]["points.ply"] = {"bytes": len(data), "blake2b": file_digest(data)}
    write_json_atomic(d / META_NAME, meta)
    return True
