"""Pointcept-preprocessed scene folders, and our own generated datasets (format ``assist3d``).

``pointcept:PATH``: PATH is one scene folder (holding ``coord.npy``), a split folder of scene
folders, or a dataset root of split folders (``train/``, ``val/``, ...; scene ids must then be
unique across splits). Per scene: ``coord.npy`` (N, 3), optional ``color.npy`` (N, 3) 0..255,
``normal.npy`` (N, 3), one of ``segment.npy`` / ``segment20.npy`` / ``segment200.npy`` (N,), and
``instance.npy`` (N,), -1 = no instance.

Which instances are objects: Pointcept's ScanNet preprocessing keeps an instance id for walls and
floors too and its evaluators skip them by semantic class. The same rule applies here: with
``segment20.npy`` the points of classes -1, 0 (wall) and 1 (floor) are not objects; with
``segment200.npy`` -1, 0 (wall) and 2 (floor); with a plain ``segment.npy`` only -1 instances are
excluded. Options (``pointcept:PATH?segment=segment200&ignore=0,2``) override the file and the
excluded classes.

``assist3d:PATH`` reads our generator's output (the same layout plus ``layout.json`` and
``meta.json`` per scene) strictly, through :func:`assist3d.export.writer.load_scene_arrays` (all of
``coord, color, normal, instance, segment`` with the writer's dtypes): every ``instance >= 0``
point is an object. The generator writes ``meta.json`` last, so folders without it (an
interrupted or running job) are skipped.

Validation (``docs/evaluation.md``, "Input validation"): arrays whose lengths disagree, empty scenes,
non-numeric arrays, non-finite or far-out coordinates, fractional or non-finite labels, and class
indices or instance ids out of range are refused; labels below -1 (e.g. an ignore index of -100)
become -1, non-finite normals zero and colours outside 0..255 are clipped, each with a warning.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from ..core.contracts import PointSample
from ..core.errors import DataError
from ..export.writer import META_NAME, load_scene_arrays
from .base import (MAX_CLASS_INDEX, MAX_INSTANCE_ID, SceneDataset, checked_coords, clean_colors, clean_normals,
                   integer_labels, read_npy)

log = logging.getLogger(__name__)

SEGMENT_FILES: tuple[str, ...] = ("segment", "segment20", "segment200")
#: Semantic classes whose instances are not objects, by segment file (Pointcept's ScanNet rule).
DEFAULT_IGNORE: dict[str, tuple[int, ...]] = {"segment": (), "segment20": (0, 1), "segment200": (0, 2)}


def _is_scene_dir(d: Path) -> bool:
    return (d / "coord.npy").is_file()


def _scene_dirs(root: Path) -> dict[str, Path]:
    if _is_scene_dir(root):
        return {root.name: root}
    dirs: dict[str, Path] = {}
    children = sorted(d for d in root.iterdir() if d.is_dir())
    scenes = [d for d in children if _is_scene_dir(d)]
    if scenes:
        return {d.name: d for d in scenes}
    for split in children:
        for d in sorted(split.iterdir()):
            if d.is_dir() and _is_scene_dir(d):
                if d.name in dirs:
                    raise DataError(f"{root}: scene {d.name!r} appears in both {dirs[d.name].parent.name}/ and {split.name}/")
                dirs[d.name] = d
    return dirs


class PointceptDataset(SceneDataset):
    """Pointcept-layout scene folders (see the module docstring)."""

    def __init__(self, root: Path, *, fmt: str = "pointcept", segment: str | None = None, ignore: str | None = None) -> None:
        root = Path(root)
        if not root.is_dir():
            raise DataError(f"{root}: {fmt} folder not found")
        if segment is not None and segment not in SEGMENT_FILES:
            raise DataError(f"{fmt}:{root}: ?segment={segment!r}; expected one of {', '.join(SEGMENT_FILES)}")
        self._segment = segment
        self._ignore: tuple[int, ...] | None = None
        if ignore is not None:
            try:
                self._ignore = tuple(int(x) for x in ignore.split(",") if x.strip())
            except ValueError:
                raise DataError(f"{fmt}:{root}: ?ignore={ignore!r} must be comma-separated integers") from None
        dirs = _scene_dirs(root)
        if fmt == "assist3d":
            # The generator writes meta.json last: a folder without it is unfinished.
            done = {k: d for k, d in dirs.items() if (d / META_NAME).is_file()}
            if len(done) < len(dirs):
                log.warning("%s: skipping %d unfinished scene folders (no meta.json)", root, len(dirs) - len(done))
            dirs = done
        self._dirs = dirs
        super().__init__(root, fmt, list(self._dirs))

    def _load(self, scene_id: str) -> PointSample:
        d = self._dirs[scene_id]
        if self.format == "assist3d":
            return _load_ours(scene_id, d)
        coord_path = d / "coord.npy"
        coord = read_npy(coord_path)
        if coord.ndim != 2 or coord.shape[1] != 3:
            raise DataError(f"{coord_path}: expected shape (N, 3), got {coord.shape}")
        coord = checked_coords(coord_path, coord)
        n = len(coord)

        def optional(name: str, shape: tuple[int, ...]) -> tuple[Path, np.ndarray] | None:
            p = d / f"{name}.npy"
            if not p.is_file():
                return None
            a = read_npy(p)
            if a.shape != shape:
                raise DataError(f"{p}: expected shape {shape} to match coord.npy, got {a.shape}")
            return p, a

        color = optional("color", (n, 3))
        normal = optional("normal", (n, 3))
        instance = optional("instance", (n,))
        seg_name = self._segment or next((s for s in SEGMENT_FILES if (d / f"{s}.npy").is_file()), None)
        segment = optional(seg_name, (n,)) if seg_name else None
        if self._segment and segment is None:
            raise DataError(f"{d / (self._segment + '.npy')}: file not found")
        segment_i = np.full(n, -1, np.int32) if segment is None else integer_labels(
            *segment, "class indices", low=-1, high=MAX_CLASS_INDEX, void_below=True)
        instance_i = np.full(n, -1, np.int32) if instance is None else integer_labels(
            *instance, "instance ids", low=-1, high=MAX_INSTANCE_ID, void_below=True)
        ignore = self._ignore
        if ignore is None:
            ignore = DEFAULT_IGNORE.get(seg_name or "segment", ()) if self.format == "pointcept" else ()
        if segment is not None and seg_name in ("segment20", "segment200") and self._ignore is None and self.format == "pointcept":
            ignore = (-1, *ignore)
        if ignore:
            instance_i[np.isin(segment_i, np.asarray(ignore, np.int32))] = -1
        return PointSample(
            scene_id=scene_id,
            coord=coord,
            color=np.zeros((n, 3), np.uint8) if color is None else _colors(*color),
            normal=np.zeros((n, 3), np.float32) if normal is None else clean_normals(*normal),
            instance=instance_i,
            segment=segment_i,
            valid=np.ones(n, bool),
        )


def _load_ours(scene_id: str, d: Path) -> PointSample:
    """A scene folder of our own format, read by the one strict reader of it
    (:func:`assist3d.export.writer.load_scene_arrays`: every array present, exact dtypes and shapes),
    then checked like any reader's input."""
    a = load_scene_arrays(d)
    return PointSample(
        scene_id=scene_id,
        coord=checked_coords(d / "coord.npy", a["coord"]),
        color=_colors(d / "color.npy", a["color"]),
        normal=clean_normals(d / "normal.npy", a["normal"]),
        instance=integer_labels(d / "instance.npy", a["instance"], "instance ids", low=-1, high=MAX_INSTANCE_ID,
                                void_below=True),
        segment=integer_labels(d / "segment.npy", a["segment"], "class indices", low=-1, high=MAX_CLASS_INDEX,
                               void_below=True),
        valid=np.ones(len(a["coord"]), bool),
    )


def _colors(path: Path, color: np.ndarray) -> np.ndarray:
    """uint8 colours from 0..255 values, or from 0..1 floats (scaled when no finite value exceeds 1)."""
    if color.dtype.kind == "f":
        finite = color[np.isfinite(color)]
        if finite.size and finite.max() <= 1.0:
            color = color * 255.0
    return clean_colors(path, color)
