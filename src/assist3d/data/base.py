"""The dataset base class every reader extends, and small checked file helpers."""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from ..contracts import PointSample
from ..errors import DataError

log = logging.getLogger(__name__)


class SceneDataset:
    """A sorted, lazily loaded collection of scenes.

    ``name`` is a short label (the folder or file stem), ``format`` the reader's format name,
    ``root`` the path the dataset was opened with, ``scene_ids`` the sorted, stable scene names.
    Subclasses set these in ``__init__`` and implement :meth:`_load`.
    """

    name: str
    format: str
    root: Path
    scene_ids: list[str]

    def __init__(self, root: Path, fmt: str, scene_ids: list[str], name: str | None = None) -> None:
        self.root = Path(root)
        self.format = fmt
        self.scene_ids = sorted(scene_ids)
        self.name = name or (self.root.stem if self.root.is_file() else self.root.name)
        if not self.scene_ids:
            raise DataError(f"{self.root}: no {fmt} scenes found")

    def __len__(self) -> int:
        return len(self.scene_ids)

    def __getitem__(self, i: int) -> PointSample:
        if not -len(self) <= i < len(self):
            raise IndexError(f"scene index {i} out of range for {len(self)} scenes")
        return self.load(self.scene_ids[i])

    def __iter__(self) -> Iterator[PointSample]:
        for sid in self.scene_ids:
            yield self.load(sid)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.format}:{self.root}, {len(self)} scenes)"

    def load(self, scene_id: str) -> PointSample:
        """Read one scene by its id (raises :class:`DataError` for an unknown id or a bad file)."""
        if scene_id not in self._id_set():
            raise DataError(f"{self.root}: no scene {scene_id!r} in this {self.format} dataset")
        return self._load(scene_id)

    def _id_set(self) -> set[str]:
        s = getattr(self, "_ids_cache", None)
        if s is None:
            s = set(self.scene_ids)
            self._ids_cache = s
        return s

    def _load(self, scene_id: str) -> PointSample:  # pragma: no cover - every reader overrides it
        raise DataError(f"{type(self).__name__} cannot load scenes")


def read_json(path: Path) -> Any:
    """Parse a JSON file; a missing or malformed file raises :class:`DataError` naming it."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror or e})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as e:
        raise DataError(f"{path}: bad JSON at line {e.lineno} column {e.colno}: {e.msg}") from None


def require_key(path: Path, obj: Any, key: str, kind: type | tuple[type, ...]) -> Any:
    """``obj[key]``, checked to exist and to be of ``kind``."""
    if not isinstance(obj, dict) or key not in obj:
        raise DataError(f"{path}: missing key {key!r}")
    value = obj[key]
    if not isinstance(value, kind):
        raise DataError(f"{path}: key {key!r} should be {kind}, got {type(value).__name__}")
    return value


def read_npy(path: Path, *, mmap: bool = False) -> np.ndarray:
    """Load a ``.npy`` file without pickles; problems raise :class:`DataError` naming the file."""
    if not path.is_file():
        raise DataError(f"{path}: file not found")
    try:
        return np.load(path, allow_pickle=False, mmap_mode="r" if mmap else None)
    except (ValueError, OSError, EOFError) as e:
        raise DataError(f"{path}: cannot load .npy ({e})") from None


def instances_from_groups(
    path: Path,
    seg_indices: np.ndarray,
    groups: list[tuple[list[int], bool, int]],
) -> tuple[np.ndarray, np.ndarray]:
    """Turn segment groups into per-point ``(instance, segment)`` int32 arrays.

    ``groups``: one ``(segment ids, is_object, class index)`` per annotated group, in file order.
    Object groups get instance ids ``0, 1, ...`` in that order; points of non-object groups keep
    instance -1 but take their class index; unannotated points are -1 in both. Vectorised: one
    ``searchsorted`` over the sorted unique segment ids.
    """
    uniq, inverse = np.unique(seg_indices, return_inverse=True)
    seg_instance = np.full(len(uniq), -1, np.int32)
    seg_class = np.full(len(uniq), -1, np.int32)
    next_id = 0
    for segs, is_object, cls in groups:
        s = np.asarray(segs, dtype=np.int64)
        if s.size == 0:
            continue
        pos = np.searchsorted(uniq, s)
        pos = np.clip(pos, 0, len(uniq) - 1)
        hit = pos[uniq[pos] == s]
        if len(hit) < len(s):
            log.debug("%s: %d segment ids of a group are not in the mesh", path, len(s) - len(hit))
        seg_class[hit] = cls
        if is_object:
            seg_instance[hit] = next_id
            next_id += 1
        else:
            seg_instance[hit] = -1
    return seg_instance[inverse].astype(np.int32), seg_class[inverse].astype(np.int32)
