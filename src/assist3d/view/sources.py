"""What a viewer page shows, read from what a user points it at: a generated scene (or a dataset
folder), a real scan file, a dataset ``FORMAT:PATH``, or a segmentation written by ``assist3d
segment`` / ``assist3d predict`` (a ``.npz`` of masks and scores), optionally over a scan."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..data import READERS, open_dataset
from ..data.ply import read_ply
from ..data.scanfile import read_scan
from ..bench.evaluation.predictions import load_predictions
from ..core import reading
from ..core.errors import ConfigError, DataError, shown
from ..export.preview import find_scene_dir
from ..export.writer import load_scene_arrays

__all__ = ["SCANNET20_NAMES", "ViewData", "load_view", "labels_from_masks", "subsample"]

#: names of the 20 ScanNet benchmark classes, by ScanNet-20 class index (the ``segment`` of the
#: ``array`` and ``scannet`` readers)
SCANNET20_NAMES: tuple[str, ...] = (
    "wall", "floor", "cabinet", "bed", "chair", "sofa", "table", "door", "window", "bookshelf", "picture",
    "counter", "desk", "curtain", "refrigerator", "shower curtain", "toilet", "sink", "bathtub", "other furniture")


@dataclass(frozen=True)
class ViewData:
    """One scene to draw. ``coord`` (N, 3) float32; ``rgb`` (N, 3) uint8 or None; ``instance`` and
    ``klass`` (N,) int32 ground truth (instance id, class index; -1 = none) or None; ``class_names``
    names class index k; ``pred`` (N,) int32 predicted instance per point (-1 = none) or None, with
    ``pred_scores`` (M,) the score of predicted instance m; ``notes`` lines shown under the title."""

    name: str
    coord: np.ndarray
    rgb: np.ndarray | None = None
    instance: np.ndarray | None = None
    klass: np.ndarray | None = None
    class_names: tuple[str, ...] = ()
    pred: np.ndarray | None = None
    pred_scores: np.ndarray | None = None
    notes: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        n = len(self.coord)
        if self.coord.ndim != 2 or self.coord.shape[1] != 3:
            raise ValueError(f"coord: expected (N, 3), got {self.coord.shape}")
        for key in ("rgb", "instance", "klass", "pred"):
            a = getattr(self, key)
            if a is not None and len(a) != n:
                raise ValueError(f"{key}: {len(a)} rows for {n} points")

    def __len__(self) -> int:
        return len(self.coord)


def labels_from_masks(masks: np.ndarray, scores: np.ndarray) -> np.ndarray:
    """(N,) int32: per point, the index of the best-scoring mask holding it (-1 = none); masks
    (M, N) bool may overlap. Ties go to the lower index."""
    n = masks.shape[1]
    out = np.full(n, -1, np.int32)
    for k in np.argsort(-np.asarray(scores, np.float64), kind="stable"):  # best first: a point keeps the first
        take = masks[k] & (out < 0)
        out[take] = k
    return out


def subsample(data: ViewData, max_points: int, seed: int = 0) -> ViewData:
    """At most ``max_points`` points of ``data`` (a seeded uniform draw, order kept); 0 = all."""
    n = len(data)
    if max_points <= 0 or n <= max_points:
        return data
    keep = np.sort(np.random.default_rng(seed).choice(n, max_points, replace=False))

    def cut(a):
        return None if a is None else a[keep]

    return replace(data, coord=data.coord[keep], rgb=cut(data.rgb), instance=cut(data.instance),
                   klass=cut(data.klass), pred=cut(data.pred),
                   notes=(*data.notes, f"showing {max_points:,} of {n:,} points (a uniform random draw; "
                                       f"--max-points 0 shows all)"))


def _is_scene_folder(p: Path) -> bool:
    return (p / "coord.npy").is_file()


def _generated_scene(path: Path, scene: str | None) -> ViewData:
    d = find_scene_dir(path, scene)
    arrays = load_scene_arrays(d)
    names: tuple[str, ...] = ()
    try:
        names = tuple(str(c) for c in reading.read_json(d / "layout.json", what="layout").get("classes") or ())
    except (DataError, AttributeError, TypeError):
        pass  # the classes then show as numbers
    return ViewData(name=d.name, coord=arrays["coord"], rgb=arrays["color"], instance=arrays["instance"],
                    klass=arrays["segment"], class_names=names,
                    notes=(f"generated scene {d}",))


def _class_names_for(fmt: str) -> tuple[str, ...]:
    return SCANNET20_NAMES if fmt in ("array", "scannet") else ()


def _dataset_scene(spec: str, scene: str | None) -> ViewData:
    ds = open_dataset(spec)
    sid = scene if scene is not None else ds.scene_ids[0]
    if sid not in ds.scene_ids:
        raise DataError(f"{spec}: no scene {shown(sid)} (it has {len(ds)}: {', '.join(ds.scene_ids[:5])}"
                        f"{', ...' if len(ds) > 5 else ''})")
    s = ds.load(sid)
    names = _class_names_for(ds.format)
    if ds.format == "assist3d":
        try:
            names = tuple(reading.read_json(ds.root / "manifest.json", what="manifest")["classes"])
        except (DataError, KeyError, TypeError):
            names = ()
    return ViewData(name=sid, coord=s.coord, rgb=s.color, instance=s.instance, klass=s.segment,
                    class_names=names, notes=(f"{ds.format} scene {sid} of {shown(spec, 200)}",))


def _scan_file(path: Path) -> ViewData:
    scan = read_scan(path)
    if scan.sample is not None:
        s = scan.sample
        return ViewData(name=scan.scene_id, coord=s.coord, rgb=s.color, instance=s.instance, klass=s.segment,
                        class_names=SCANNET20_NAMES, notes=(f"scan {path} (ScanNet-20 labels)",))
    coord = np.asarray(scan.coord, np.float32)
    instance = None
    if path.suffix.lower() == ".ply":  # `assist3d segment` writes each point's instance as a vertex property
        v = read_ply(path).vertex
        if "instance" in (v.dtype.names or ()):
            instance = np.asarray(v["instance"]).astype(np.int32)
    data = ViewData(name=scan.scene_id, coord=coord, rgb=scan.color, notes=(f"scan {path}",))
    if instance is not None:  # a segment PLY: its instances are a prediction, its colours are not the scan's
        data = replace(data, rgb=None, pred=instance, notes=(*data.notes, "instances from the PLY's 'instance' property"))
    return data


def _finite_only(data: ViewData) -> ViewData:
    """``data`` without its points whose coordinates are not finite (a raw scan may hold some)."""
    keep = np.isfinite(data.coord).all(axis=1)
    if keep.all():
        return data

    def cut(a):
        return None if a is None else a[keep]

    return replace(data, coord=data.coord[keep], rgb=cut(data.rgb), instance=cut(data.instance),
                   klass=cut(data.klass), pred=cut(data.pred),
                   notes=(*data.notes, f"{int((~keep).sum()):,} points with non-finite coordinates left out"))


def _with_prediction(data: ViewData, npz: Path) -> ViewData:
    masks, scores = load_predictions(npz, len(data))
    return replace(data, pred=labels_from_masks(masks, scores), pred_scores=np.asarray(scores, np.float32),
                   notes=(*data.notes, f"prediction {npz}: {len(scores)} instances"))


def load_view(path: str, *, pred: Path | None = None, scene: str | None = None) -> ViewData:
    """The scene that ``path`` names, with the prediction ``pred`` (a masks/scores ``.npz`` over the
    same points) when given. ``path``: a generated scene folder or dataset folder (``scene`` picks a
    scene, default the first), a ``.ply`` or ``(N, 3|6|8)`` ``.npy`` scan, ``FORMAT:PATH``, or a
    segmentation ``.npz`` (its points come from the ``.ply`` of the same name beside it, which
    ``assist3d segment`` writes, unless ``pred`` is used with a scan instead)."""
    p = Path(path)
    if p.suffix.lower() == ".npz" and p.is_file():
        if pred is not None:
            raise ConfigError(f"{p}: a prediction file is given twice (as PATH and --pred); give the scan as PATH")
        ply = p.with_suffix(".ply")
        if not ply.is_file():
            raise DataError(f"{p}: no {ply.name} beside it to take the points from; give the scan as PATH and "
                            f"this file as --pred")
        return _finite_only(_with_prediction(replace(_scan_file(ply), pred=None), p))
    if p.exists():
        if p.is_dir():
            if _is_scene_folder(p) or any(_is_scene_folder(q) for q in p.iterdir() if q.is_dir()):
                data = _generated_scene(p, scene)
            elif any(p.glob("*.npz")) and not any(p.glob("*.npy")):
                npz = sorted(p.glob("*.npz"))
                pick = next((q for q in npz if q.stem == scene), None) if scene else npz[0]
                if pick is None:
                    raise DataError(f"{p}: no {shown(scene)}.npz in this folder")
                return load_view(str(pick), pred=pred)
            else:
                raise DataError(f"{p}: not a scene folder, a dataset folder or a folder of segment outputs "
                                f"(for other datasets give FORMAT:PATH)")
        else:
            data = _scan_file(p)
    elif ":" in path and path.split(":", 1)[0].strip().lower() in READERS:
        data = _dataset_scene(path, scene)
    else:
        raise DataError(f"{path}: not found")
    return _finite_only(_with_prediction(data, pred) if pred is not None else data)
