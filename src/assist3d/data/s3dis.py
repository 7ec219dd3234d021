"""S3DIS rooms from their ``Annotations`` text files.

``s3dis:PATH``: PATH is ``Stanford3dDataset_v1.2_Aligned_Version`` (holding ``Area_1`` ...
``Area_6``), its parent, one ``Area_N`` folder, or one room folder. Each room's
``Annotations/<class>_<k>.txt`` holds one point per line, ``x y z r g b``; every file is one
instance. Scene ids are ``Area_N_<room>`` (e.g. ``Area_5_office_1``). Points are the annotation
files concatenated in (class, k) order.

Objects (class-agnostic): every class except ``ceiling``, ``floor`` and ``wall`` -- the structural
surfaces, mirroring ScanNet's exclusion of wall and floor. ``beam``, ``column``, ``window``,
``door``, ``board`` and ``clutter`` are objects (door and window are objects in ScanNet's 18
classes too; beams and columns are discrete, countable elements). ``segment`` is the index in
:data:`S3DIS_CLASSES`; ``stairs`` files count as ``clutter``.

Parsing text is slow (numpy reads about 0.2-0.3 M points per second here), so ``s3dis:PATH?cache=1``
keeps each parsed room as an ``.npz`` under ``<cache_root>/s3dis/``, keyed by the room's path and
its files' sizes and modification times (about 23 bytes per point).

The v1.2 release has one corrupt line (``Area_5/hallway_6/Annotations/ceiling_1.txt`` row 180389,
a stray character inside a number). Characters that cannot belong to a number are removed and a
warning names the file and line; any other malformed content raises :class:`DataError`, and so do
non-finite or far-out coordinates and a room without points. Colours outside 0..255 are clipped
with a warning.
"""

from __future__ import annotations

import hashlib
import io
import logging
import re
import warnings
from pathlib import Path

import numpy as np

from ..core.contracts import PointSample
from ..core import reading
from ..core.errors import ConfigError, DataError, shown
from ..core.fileio import write_bytes_atomic
from ..core.paths import cache_root
from .base import SceneDataset, checked_coords, clean_colors

log = logging.getLogger(__name__)

S3DIS_CLASSES: tuple[str, ...] = (
    "ceiling", "floor", "wall", "beam", "column", "window", "door",
    "table", "chair", "sofa", "bookcase", "board", "clutter",
)
S3DIS_STUFF: frozenset[str] = frozenset({"ceiling", "floor", "wall"})
RELEASE_DIR = "Stanford3dDataset_v1.2_Aligned_Version"
_ANNO = re.compile(r"^(?P<cls>[A-Za-z]+)_(?P<k>\d+)\.txt$")
_STRAY = re.compile(rb"[^0-9eE+\-.\s]")


def _room_dirs(root: Path) -> dict[str, Path]:
    if (root / "Annotations").is_dir():
        return {f"{root.parent.name}_{root.name}": root}
    if root.name.startswith("Area_") and root.is_dir():
        areas = [root]
    else:
        base = root / RELEASE_DIR if (root / RELEASE_DIR).is_dir() else root
        areas = sorted(d for d in base.iterdir() if d.is_dir() and d.name.startswith("Area_"))
    rooms: dict[str, Path] = {}
    for area in areas:
        for room in sorted(area.iterdir()):
            if room.is_dir() and (room / "Annotations").is_dir():
                rooms[f"{area.name}_{room.name}"] = room
    return rooms


def read_s3dis_txt(path: Path) -> np.ndarray:
    """One annotation file as an ``(n, 6) float32`` array, tolerating stray characters."""
    raw = reading.read_bytes(path, limit=reading.MAX_TEXT_BYTES, what="S3DIS annotation file")
    if _STRAY.search(raw) is not None:
        for m in _STRAY.finditer(raw):
            line = raw.count(b"\n", 0, m.start()) + 1
            log.warning("%s: line %d: removed stray character %r", path, line, m.group())
        raw = _STRAY.sub(b"", raw)
    if not raw.strip():
        return np.zeros((0, 6), np.float32)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            arr = np.loadtxt(io.BytesIO(raw), dtype=np.float32, ndmin=2)
    except ValueError as e:
        raise DataError(f"{path}: malformed S3DIS annotation file ({shown(e)})") from None
    if arr.shape[1] != 6:
        raise DataError(f"{path}: expected 6 columns (x y z r g b), found {arr.shape[1]}")
    checked_coords(path, arr[:, :3])
    return arr


class S3DISDataset(SceneDataset):
    """S3DIS (see the module docstring for layout and the object rule)."""

    def __init__(self, root: Path, *, cache: str | None = None) -> None:
        root = Path(root)
        if not root.is_dir():
            raise DataError(f"{root}: S3DIS folder not found")
        if cache not in (None, "0", "1"):
            raise ConfigError(f"s3dis:{root}: ?cache={cache!r}; expected 0 or 1")
        self._cache = cache == "1"
        self._rooms = _room_dirs(root)
        super().__init__(root, "s3dis", list(self._rooms))

    def _load(self, scene_id: str) -> PointSample:
        anno = self._rooms[scene_id] / "Annotations"
        if not self._cache:
            return self._parse(scene_id, anno)
        files = sorted(anno.glob("*.txt"))
        h = hashlib.blake2b(str(anno.resolve()).encode(), digest_size=16)
        for f in files:
            st = f.stat()
            h.update(f"{f.name}:{st.st_size}:{st.st_mtime_ns};".encode())
        path = cache_root() / "s3dis" / f"{scene_id}-{h.hexdigest()}.npz"
        if path.is_file():
            try:
                z = reading.read_npz(path, keys=("coord", "color", "instance", "segment"))
                n = len(z["coord"])
                return PointSample(scene_id=scene_id, coord=z["coord"], color=z["color"],
                                   normal=np.zeros((n, 3), np.float32), instance=z["instance"],
                                   segment=z["segment"], valid=np.ones(n, bool))
            except (DataError, ValueError, TypeError) as e:
                log.warning("%s: unreadable cache entry, parsing again (%s)", path, e)
        sample = self._parse(scene_id, anno)
        buf = io.BytesIO()
        np.savez(buf, coord=sample.coord, color=sample.color, instance=sample.instance, segment=sample.segment)
        write_bytes_atomic(path, buf.getvalue())
        return sample

    def _parse(self, scene_id: str, anno: Path) -> PointSample:
        files: list[tuple[int, int, str, Path]] = []
        for f in anno.iterdir():
            m = _ANNO.match(f.name)
            if not m:
                continue
            cls = m["cls"].lower()
            if cls == "stairs":
                cls = "clutter"
            if cls not in S3DIS_CLASSES:
                raise DataError(f"{f}: unknown S3DIS class '{shown(m['cls'])}' (expected one of {', '.join(S3DIS_CLASSES)})")
            files.append((S3DIS_CLASSES.index(cls), int(m["k"]), m["cls"].lower(), f))
        if not files:
            raise DataError(f"{anno}: no <class>_<k>.txt annotation files")
        files.sort(key=lambda t: (t[2], t[1]))
        parts: list[np.ndarray] = []
        colors: list[np.ndarray] = []
        instance: list[np.ndarray] = []
        segment: list[np.ndarray] = []
        next_id = 0
        for cls_idx, _k, _name, f in files:
            pts = read_s3dis_txt(f)
            parts.append(pts)
            colors.append(clean_colors(f, pts[:, 3:6]))
            if S3DIS_CLASSES[cls_idx] in S3DIS_STUFF:
                instance.append(np.full(len(pts), -1, np.int32))
            else:
                instance.append(np.full(len(pts), next_id, np.int32))
                next_id += 1
            segment.append(np.full(len(pts), cls_idx, np.int32))
        data = np.concatenate(parts)
        n = len(data)
        if n == 0:
            raise DataError(f"{anno}: no points (every annotation file is empty)")
        return PointSample(
            scene_id=scene_id,
            coord=np.ascontiguousarray(data[:, :3], dtype=np.float32),
            color=np.concatenate(colors),
            normal=np.zeros((n, 3), np.float32),
            instance=np.concatenate(instance),
            segment=np.concatenate(segment),
            valid=np.ones(n, bool),
        )
