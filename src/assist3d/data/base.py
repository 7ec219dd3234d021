"""The dataset base class every reader extends, and small checked file and array helpers.

The array helpers hold the readers' shared validation policy (see "Input validation" in
``docs/evaluation.md``): what defines the scene (coordinates, labels) is refused with a
:class:`DataError` naming the file when it is wrong; what only decorates it (colours, normals) is
cleaned with one warning that says how many points changed.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from ..core.contracts import PointSample
from ..core import reading
from ..core.errors import ConfigError, DataError, shown

log = logging.getLogger(__name__)

#: Largest accepted |coordinate|, metres: no indoor scan is 100 km across, and float32 cannot
#: resolve centimetres beyond it (a georeferenced scan must be re-centred first).
MAX_COORD_M = 1.0e5
#: Largest accepted semantic class index (nyu40 ids reach 40, ScanNet200 indices 199).
MAX_CLASS_INDEX = 65_535
#: Largest accepted instance id (ids are stored as int32).
MAX_INSTANCE_ID = int(np.iinfo(np.int32).max)
#: numpy type kinds that hold real numbers: signed and unsigned integers, floats.
REAL_KINDS = "iuf"
#: Which instances a ScanNet-protocol reader counts as objects (its ``?objects=`` option):
#: ``benchmark``, the 18 benchmark classes (evaluation); ``annotated``, every annotated instance but
#: the room's structure (arrangement statistics, where generated scans label every object).
OBJECT_POLICIES: tuple[str, ...] = ("benchmark", "annotated")


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


def object_policy(dataset: str, value: str) -> str:
    """The ``?objects=`` option of ``dataset`` checked against :data:`OBJECT_POLICIES`."""
    if value not in OBJECT_POLICIES:
        raise ConfigError(f"dataset {dataset}: ?objects={value!r} must be one of {', '.join(OBJECT_POLICIES)}")
    return value


def read_json(path: Path) -> Any:
    """Parse a JSON file; a missing, malformed, oversized or over-nested file raises
    :class:`DataError` naming it (see :mod:`assist3d.core.reading`)."""
    return reading.read_json(path)


def require_key(path: Path, obj: Any, key: str, kind: type | tuple[type, ...]) -> Any:
    """``obj[key]``, checked to exist and to be of ``kind``."""
    if not isinstance(obj, dict) or key not in obj:
        raise DataError(f"{path}: missing key {key!r}")
    value = obj[key]
    if not isinstance(value, kind):
        raise DataError(f"{path}: key {key!r} should be {kind}, got {type(value).__name__}")
    return value


def read_npy(path: Path, *, mmap: bool = False) -> np.ndarray:
    """Load a ``.npy`` file without pickles; problems raise :class:`DataError` naming the file
    (object arrays, truncated files and forged shapes are refused from the header: see
    :func:`assist3d.core.reading.read_npy`)."""
    return reading.read_npy(path, mmap=mmap)


# ------------------------------------------------------------------------------------------------
# Array validation shared by the readers


def _rows(mask: np.ndarray) -> tuple[int, int]:
    """(how many rows are set, the first one)."""
    hits = np.flatnonzero(mask)
    return len(hits), int(hits[0]) if len(hits) else -1


def require_real(path: Path, a: np.ndarray, what: str) -> None:
    """:class:`DataError` unless ``a`` holds real numbers (ints or floats; not bool, complex, text)."""
    if a.dtype.kind not in REAL_KINDS:
        raise DataError(f"{path}: {what} must be real numbers (int or float), got dtype {a.dtype}")


def checked_coords(path: Path, a: np.ndarray, what: str = "coordinates") -> np.ndarray:
    """``(N, 3)`` float32 coordinates; :class:`DataError` naming ``path`` for an empty scan,
    non-numbers, non-finite values (also float64 values too large for float32) or values beyond
    :data:`MAX_COORD_M`."""
    require_real(path, a, what)
    if len(a) == 0:
        raise DataError(f"{path}: no points (an empty scan)")
    with np.errstate(over="ignore", invalid="ignore"):
        c = np.ascontiguousarray(a, dtype=np.float32)
    k, i = _rows(~np.isfinite(c).all(axis=1))
    if k:
        raise DataError(f"{path}: {k} of {len(c)} points have non-finite {what} (NaN, inf or beyond float32; "
                        f"first at row {i})")
    k, i = _rows((np.abs(c) > MAX_COORD_M).any(axis=1))
    if k:
        raise DataError(f"{path}: {k} of {len(c)} points have {what} beyond ±{MAX_COORD_M:.0e} m (first at row {i}: "
                        f"{c[i].tolist()}); re-centre the scan")
    return c


def integer_labels(path: Path, a: np.ndarray, what: str, *, low: int, high: int,
                   void_below: bool = False) -> np.ndarray:
    """``(N,)`` int32 labels from an integer or float array.

    Refused (:class:`DataError` naming ``path``): non-numbers, non-finite or fractional values,
    values above ``high``, and values below ``low`` unless ``void_below``, in which case they
    become -1 (void) with one warning giving their count.
    """
    require_real(path, a, what)
    n = len(a)
    if a.dtype.kind == "f":
        a = a.astype(np.float64)  # exact for every float type; compares with int32 bounds without overflow
        k, i = _rows(~np.isfinite(a))
        if k:
            raise DataError(f"{path}: {k} of {n} {what} are not finite (first at row {i})")
        k, i = _rows(a != np.rint(a))
        if k:
            raise DataError(f"{path}: {k} of {n} {what} are not integers (first at row {i}: {a[i].item()!r})")
    k, i = _rows(a > high)
    if k:
        raise DataError(f"{path}: {k} of {n} {what} are above {high} (first at row {i}: {a[i].item()!r})")
    below = a < low
    k, i = _rows(below)
    if k and not void_below:
        raise DataError(f"{path}: {k} of {n} {what} are below {low} (first at row {i}: {a[i].item()!r})")
    out = a.astype(np.int32)
    if k:
        log.warning("%s: %d of %d %s are below %d (first at row %d: %r); treated as void (-1)",
                    path, k, n, what, low, i, a[i].item())
        out[below] = -1
    return out


def clean_colors(path: Path, c: np.ndarray) -> np.ndarray:
    """``(N, 3)`` uint8 colours from 0..255 values: non-finite values become 0 and values outside
    0..255 are clipped, with one warning giving how many points changed. Non-numbers are refused."""
    require_real(path, c, "colours")
    if c.dtype == np.uint8:
        return np.ascontiguousarray(c)
    f = np.rint(c.astype(np.float64))
    nonfinite = ~np.isfinite(f)
    outside = ~nonfinite & ((f < 0) | (f > 255))
    changed = (nonfinite | outside).any(axis=1) if f.ndim == 2 else nonfinite | outside
    if changed.any():
        log.warning("%s: %d of %d points have colour values that are non-finite (%d values, set to 0) or outside "
                    "0..255 (%d values, clipped)", path, int(changed.sum()), len(f), int(nonfinite.sum()),
                    int(outside.sum()))
        f[nonfinite] = 0
    return np.clip(f, 0, 255).astype(np.uint8)


def clean_normals(path: Path, a: np.ndarray) -> np.ndarray:
    """``(N, 3)`` float32 normals; rows with a non-finite value become zeros (= unknown) with one
    warning giving their count. Non-numbers are refused."""
    require_real(path, a, "normals")
    with np.errstate(over="ignore", invalid="ignore"):
        out = np.array(a, dtype=np.float32)
    bad = ~np.isfinite(out).all(axis=1)
    k, i = _rows(bad)
    if k:
        log.warning("%s: %d of %d points have non-finite normals (first at row %d); set to zero (unknown)",
                    path, k, len(out), i)
        out[bad] = 0
    return out


def integer_list(path: Path, key: str, values: list) -> np.ndarray:
    """A JSON list of integers (e.g. ``segIndices``) as int64; :class:`DataError` naming ``path``
    and ``key`` for nested lists, non-numbers, fractions or values beyond int64."""
    try:
        a = np.asarray(values)
    except (ValueError, OverflowError, TypeError):
        raise DataError(f"{path}: {key!r} must be a flat list of integers") from None
    if a.size == 0:
        return np.zeros(0, np.int64)
    if a.ndim != 1 or a.dtype.kind not in REAL_KINDS:
        raise DataError(f"{path}: {key!r} must be a flat list of integers (found {shown(values[:3], 80)} ...)")
    if a.dtype.kind == "f":
        k, i = _rows(~np.isfinite(a) | (a != np.rint(a)) | (np.abs(a) > 2.0**62))
        if k:
            raise DataError(f"{path}: {key!r} holds {k} values that are not integers "
                            f"(first at position {i}: {a[i].item()!r})")
    if a.dtype.kind == "u" and a.max() > np.iinfo(np.int64).max:
        raise DataError(f"{path}: {key!r} holds values beyond the int64 range")
    return a.astype(np.int64)


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
        s = integer_list(path, "segments", segs)
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
