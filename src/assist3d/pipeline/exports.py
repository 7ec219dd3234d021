"""A generated dataset written out in other file formats, scene by scene (``assist3d export``)."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

from ..core.errors import ConfigError, DataError, shown
from ..export.ply import ply_bytes
from ..core.fileio import write_bytes_atomic
from ..export.writer import export_scene_ply, read_scene_meta, scene_sample
from .dataset import _folder_lock

log = logging.getLogger(__name__)

__all__ = ["ExportRun", "dataset_scenes", "export_dataset_ply"]

PLY_COLORS = ("instance", "rgb")


@dataclass
class ExportRun:
    """What an export did: files ``written``, files ``kept`` (there already), scenes ``skipped`` with why."""

    written: list[str] = field(default_factory=list)
    kept: list[str] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)


def dataset_scenes(path: str | Path, only: list[str] | None = None) -> tuple[Path, list[Path]]:
    """(the dataset folder, its scene folders in order) for a dataset folder or one scene folder;
    ``only`` picks scenes by id. A :class:`DataError` naming the path when there are none."""
    p = Path(path)
    if (p / "coord.npy").is_file():
        scenes, root = [p], p.parent
    elif p.is_dir():
        root = p
        scenes = sorted(q for q in p.iterdir() if q.is_dir() and (q / "coord.npy").is_file())
    else:
        raise DataError(f"{p}: not found" if not p.exists() else f"{p}: not a dataset or scene folder")
    if only:
        by_name = {q.name: q for q in scenes}
        missing = [s for s in only if s not in by_name]
        if missing:
            raise DataError(f"{p}: no scene {shown(missing[0])} (expected a folder with coord.npy)")
        scenes = [by_name[s] for s in only]
    if not scenes:
        raise DataError(f"{p}: no scene folders (with coord.npy) found")
    return root, scenes


def export_dataset_ply(path: str | Path, out: str | Path | None = None, *, color_by: str = "instance",
                       only: list[str] | None = None) -> ExportRun:
    """Every finished scene of the dataset (or scene folder) ``path`` as a binary PLY with x y z, colour,
    instance and segment per point. Without ``out``: ``points.ply`` in each scene folder, coloured by
    instance and listed in its ``meta.json`` (what ``generate --ply`` writes; a scene that has one keeps
    it), under the dataset's lock. With ``out``: ``out/<scene>.ply``, coloured by ``color_by``
    (``instance`` or ``rgb``), the dataset untouched. Unfinished scenes are skipped and named."""
    if color_by not in PLY_COLORS:
        raise ConfigError(f"--color-by {color_by!r}: expected one of {', '.join(PLY_COLORS)}")
    root, scenes = dataset_scenes(path, only)
    run = ExportRun()
    if out is None:
        if color_by != "instance":
            raise ConfigError("--color-by rgb needs --out DIR: the points.ply inside a scene folder is the one "
                              "`generate --ply` writes, coloured by instance")
        with _folder_lock(root):
            for d in scenes:
                try:
                    (run.written if export_scene_ply(d) else run.kept).append(str(d / "points.ply"))
                except DataError as e:
                    run.skipped[d.name] = str(e)
        return run
    target = Path(out)
    if target.exists() and not target.is_dir():
        raise ConfigError(f"--out {target}: exists and is not a folder")
    target.mkdir(parents=True, exist_ok=True)
    for d in scenes:
        if read_scene_meta(d) is None:
            run.skipped[d.name] = f"{d}: not a finished scene (no valid meta.json, or a file it lists is missing " \
                                  "or changed); re-run `assist3d generate` to complete it"
            continue
        write_bytes_atomic(target / f"{d.name}.ply", ply_bytes(scene_sample(d), color_by=color_by))
        run.written.append(str(target / f"{d.name}.ply"))
    return run
