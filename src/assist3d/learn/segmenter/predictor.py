"""Segment a scan from Python: ``Predictor.load(path).segment(points) -> Segmentation``.

The use case behind ``assist3d segment``, as a library call::

    from assist3d.learn.segmenter.predictor import Predictor

    predictor = Predictor.load()                       # the shipped model, hybrid inference
    seg = predictor.segment(xyz, rgb)                  # (N, 3) float metres z up, (N, 3) uint8 or None
    seg.masks, seg.scores, seg.labels                  # (M, N) bool, (M,) float32, (N,) int64

What runs after the network is a **post-processing step** chosen by name from :data:`STEPS`
(``hybrid``: the network's instances with the geometric components and superpoint snapping, the
``segment`` default; ``learned``: the network's instances alone; ``geometric``: planes removed and
connected components, no network). Add one with ``STEPS.add("name", Step(run))``, ``run`` a function
``(model, config, coord, color, *, tta) -> Segmentation``; ``Step(run, needs_model=False)`` runs without
weights.

``segment`` takes a scan as a user has it: points with non-finite or far-out coordinates get no
instance (one warning), another up axis or unit is turned into metres with z up before the network
sees it (``up_axis``, ``units``), and the masks come back over every input point.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator, Sequence

import numpy as np
import torch

from ...data import READERS, open_dataset
from ...data.base import MAX_COORD_M
from ...data.ply import write_ply
from ...data.scanfile import ScanFile, read_scan
from ...bench.evaluation.ap import match_scene, summarize
from ...bench.evaluation.predictions import save_predictions
from ...core.errors import DataError, shown
from ...core.paths import safe_name
from ...core.registry import Registry
from ...export.segmentation import instance_colors, write_top_view
from ..engine.voxelize import VoxelGridError
from ..checkpoint import read_checkpoint
from ..engine.config import TrainConfig
from ..engine.predict import LoadedMask3D, mask3d_from_checkpoint, predict_points
from .checkpoint import LoadedSegmenter, load_segmenters, segmenter_from_checkpoint
from .config import SegmenterConfig
from .features import UNITS, to_segmenter_frame
from .geometric import segment_geometric
from .hybrid import segment_hybrid
from .infer import Segmentation, segment_points
from .model import Network
from .shipped import shipped_model_path

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Step:
    """A post-processing step: ``run(model, config, coord, color, *, tta) -> Segmentation`` on a scan
    in metres with z up; ``needs_model`` False for steps that use no network; ``models``: the registry
    names of the models whose outputs it works on."""

    run: Callable[..., Segmentation]
    needs_model: bool = True
    models: frozenset[str] = frozenset({"segmenter"})


def _mask3d_instances(model, cfg: TrainConfig, coord: np.ndarray, color: np.ndarray | None, *,
                      tta: bool = False) -> Segmentation:
    """The Mask3D-style model's own instances (its ``predict`` settings), as a :class:`Segmentation`."""
    if tta:
        raise DataError("test-time augmentation (segment --tta) is for the CPU segmenter, not a mask3d model")
    n = len(coord)
    rgb = np.asarray(color, np.uint8) if color is not None else np.zeros((n, 3), np.uint8)
    pred = predict_points(model, coord, rgb, cfg.data.voxel_size, cfg.predict, next(model.parameters()).device.type)
    labels = np.full(n, -1, np.int64)
    for i in range(len(pred.scores) - 1, -1, -1):  # the best-scoring mask names a point held by several
        labels[pred.masks[i]] = i
    return Segmentation(masks=pred.masks, scores=pred.scores, labels=labels)


def _network_instances(model, cfg, coord, color, *, tta=False) -> Segmentation:
    if isinstance(cfg, TrainConfig):
        return _mask3d_instances(model, cfg, coord, color, tta=tta)
    return segment_points(model, cfg, coord, color, tta=tta)


#: post-processing steps by name (``assist3d segment --method NAME``)
STEPS: Registry[Step] = Registry("post-processing step")
STEPS.add("hybrid", Step(lambda model, cfg, coord, color, *, tta=False: segment_hybrid(model, cfg, coord, color, tta=tta)))
STEPS.add("learned", Step(_network_instances, models=frozenset({"segmenter", "mask3d"})))
STEPS.add("geometric", Step(lambda model, cfg, coord, color, *, tta=False: segment_geometric(coord), needs_model=False,
                            models=frozenset()))

#: ``segment``'s step when none is named: the network's instances alone, chosen over hybrid by the rule
#: written before the scaling runs (docs/results.md, "The shipped model and segment's default")
DEFAULT_METHOD = "learned"


def usable_points(where: str, scene_id: str, coord: np.ndarray, units: str = "m") -> np.ndarray:
    """(N,) bool: the points to segment, those with finite coordinates within ``MAX_COORD_M`` metres
    (``coord`` is in ``units``, so the limit is taken in those units); the others get no instance,
    with one warning giving their count. DataError when none is left."""
    limit = MAX_COORD_M / UNITS[units]
    with np.errstate(invalid="ignore"):
        ok = np.all(np.isfinite(coord) & (np.abs(coord) <= limit), axis=1)
    if not ok.all():
        log.warning("%s: %d of %d points have non-finite coordinates or lie beyond ±%.0e m; they get no instance",
                    shown(scene_id), int((~ok).sum()), len(coord), MAX_COORD_M)
        if not ok.any():
            raise DataError(f"{where}: scene {shown(scene_id)}: no point has finite coordinates "
                            f"within ±{MAX_COORD_M:.0e} m")
    return ok


def frame_hint(frame: np.ndarray) -> str | None:
    """Why a scan, already in the segmenter's frame, may not be metres with z up, or None. Robust
    extents (1st-99th percentile): an indoor scan taller along z than 3.5 m and than its shorter
    horizontal side is more likely lying on its side (a y-up export); one wider than 200 m is more
    likely in centimetres. A hint for a warning, never an error: atriums and halls exist."""
    if len(frame) < 100:
        return None
    lo, hi = np.percentile(frame, [1.0, 99.0], axis=0)
    ext = hi - lo
    if ext.max() > 200.0:
        return (f"it spans {ext.max():.0f} m along an axis, more than an indoor scan; "
                f"if it is not in metres, give --units cm or --units mm")
    if ext[2] > 3.5 and ext[2] > min(ext[0], ext[1]):
        return (f"it is {ext[2]:.1f} m tall along z but {min(ext[0], ext[1]):.1f} m wide along "
                f"{'xy'[int(np.argmin(ext[:2]))]}; if z is not its up axis, give --up-axis (e.g. y)")
    return None


@dataclass(frozen=True)
class ScanSegmentation(Segmentation):
    """A :class:`Segmentation` over every input point (``masks`` (M, N), ``labels`` (N,)), with
    ``segmented`` (N,) bool: the points the method saw, and ``frame`` (K, 3) float32: those points in
    the segmenter's frame (metres, z up; what a top view draws)."""

    segmented: np.ndarray = None  # type: ignore[assignment]
    frame: np.ndarray = None  # type: ignore[assignment]


class Predictor:
    """A segmenter (or none, for the geometric step) and the post-processing step that runs after it."""

    def __init__(self, loaded: LoadedSegmenter | LoadedMask3D | None, method: str = DEFAULT_METHOD, *, tta: bool = False,
                 device: str = "cpu") -> None:
        self.step = STEPS.get(method)
        self.method = method
        if self.step.needs_model and loaded is None:
            raise DataError(f"post-processing step {method!r} needs a model")
        if self.step.needs_model and loaded.name not in self.step.models:
            works = [name for name in STEPS.names() if loaded.name in STEPS.get(name).models]
            raise DataError(f"post-processing step {method!r} works on the outputs of a {'/'.join(sorted(self.step.models))} "
                            f"model, not a {loaded.name} model: use --method {' or '.join(works)}")
        if tta and loaded is not None and loaded.name != "segmenter":
            raise DataError(f"test-time augmentation (segment --tta) is for the CPU segmenter, not a {loaded.name} model")
        if not self.step.needs_model and tta:
            raise DataError(f"test-time augmentation (segment --tta) is for a network; step {method!r} has none")
        self.loaded = loaded if self.step.needs_model else None
        self.tta = tta
        self.device = device

    @classmethod
    def load(cls, checkpoints: str | Path | Sequence[str | Path] | None = None, *, method: str = DEFAULT_METHOD,
             tta: bool = False, device: str = "cpu") -> "Predictor":
        """The model in ``checkpoints`` (several files: an ensemble; None: the shipped model), or no
        model for a step that needs none."""
        step = STEPS.get(method)
        if not step.needs_model:
            if checkpoints:
                raise DataError(f"a checkpoint (segment --checkpoint) is for a step with a network; {method!r} has no weights")
            return cls(None, method, tta=tta, device=device)
        if checkpoints is None:
            paths: list[str | Path] = [shipped_model_path()]
        elif isinstance(checkpoints, (str, Path)):
            paths = [checkpoints]
        else:
            paths = list(checkpoints)
        if len(paths) > 1:
            return cls(load_segmenters(paths, device), method, tta=tta, device=device)
        path = Path(paths[0])
        ckpt = read_checkpoint(path, device)  # any model of the registry: the file names it
        if ckpt.model == "segmenter":
            return cls(segmenter_from_checkpoint(ckpt, path, device), method, tta=tta, device=device)
        if ckpt.model == "mask3d":
            return cls(mask3d_from_checkpoint(ckpt, device), method, tta=tta, device=device)
        raise DataError(f"{path}: a {ckpt.model} checkpoint; segment runs segmenter and mask3d models")

    @property
    def model(self) -> Network | torch.nn.Module | None:
        return self.loaded.model if self.loaded is not None else None

    @property
    def config(self) -> SegmenterConfig | TrainConfig | None:
        return self.loaded.config if self.loaded is not None else None

    def segment(self, coord: np.ndarray, color: np.ndarray | None = None, *, up_axis: str = "z", units: str = "m",
                name: str = "scan", where: str = "input") -> ScanSegmentation:
        """Instances of one scan: ``coord`` (N, 3) in ``units`` with ``up_axis`` up, ``color`` (N, 3)
        uint8 or None; ``name`` (the scene id) and ``where`` (its file or dataset) name it in messages."""
        coord = np.asarray(coord, np.float32)
        if coord.ndim != 2 or coord.shape[1] != 3:
            raise DataError(f"{where}: scene {shown(name)}: expected (N, 3) coordinates, got shape {coord.shape}")
        if len(coord) == 0:
            raise DataError(f"{where}: scene {shown(name)} has no points")
        ok = usable_points(where, name, coord, units)
        frame = to_segmenter_frame(coord[ok], up_axis, units)
        hint = frame_hint(frame)
        if hint:
            log.warning("%s: scene %s: %s", shown(where), shown(name), hint)
        sub_color = color[ok] if color is not None else None
        try:
            seg = self.step.run(self.model, self.config, frame, sub_color, tta=self.tta)
        except VoxelGridError as e:  # a scan too large for the voxel grid, e.g. millimetres read as metres
            fix = "give --units mm or cm if it is not in metres" if units == "m" else f"it was read in {units}: check --units"
            raise DataError(f"{where}: scene {shown(name)}: {e}; {fix}") from None
        masks = np.zeros((len(seg.scores), len(coord)), bool)
        masks[:, ok] = seg.masks
        labels = np.full(len(coord), -1, np.int64)
        labels[ok] = seg.labels
        return ScanSegmentation(masks=masks, scores=seg.scores, labels=labels, segmented=ok, frame=frame)


def scan_inputs(spec: str) -> Iterator[ScanFile]:
    """The scans of ``spec``: one ``.ply`` / ``.npy`` file (:func:`read_scan`), or every scene of a
    dataset ``FORMAT:PATH`` (with its ground truth)."""
    if spec.split(":", 1)[0].strip().lower() not in READERS or Path(spec).exists():
        yield read_scan(Path(spec))
        return
    ds = open_dataset(spec)
    for sid in ds.scene_ids:
        s = ds.load(sid)
        yield ScanFile(sid, s.coord, s.color, s)


def segment_scan(spec: str, out: str | Path, predictor: Predictor, *, png: bool = False, up_axis: str = "z",
                 units: str = "m") -> Iterator[dict]:
    """Segment every scan of ``spec`` (a file or ``FORMAT:PATH``) into ``out``: ``<scene_id>.npz``
    (masks over the input points, scores), ``<scene_id>.ply`` (the points coloured by instance, each
    vertex's instance index in an ``instance`` property, -1 = none) and, with ``png``, a top view.
    Yields one row a scan: ``scene, points, instances, seconds, npz, ply`` (``png`` too), ``files`` (every
    file written, in order) and, where the scan has ground truth, ``AP, AP50, AP25, AR`` (ScanNet
    protocol)."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise DataError(f"{out}: exists and is not a folder")
    for scan in scan_inputs(spec):
        t0 = time.perf_counter()
        scene_id = scan.scene_id
        safe_name(scene_id, what=f"{spec}: scene id")
        coord = np.asarray(scan.coord, np.float32)
        seg = predictor.segment(coord, scan.color, up_axis=up_axis, units=units, name=scene_id, where=spec)
        seconds = time.perf_counter() - t0
        out.mkdir(parents=True, exist_ok=True)
        files = {"npz": out / f"{scene_id}.npz", "ply": out / f"{scene_id}.ply"}
        save_predictions(files["npz"], seg.masks, seg.scores)
        colors = instance_colors(seg.labels)
        write_ply(files["ply"], np.where(seg.segmented[:, None], coord, 0).astype(np.float32), colors,
                  instance=seg.labels.astype(np.int32))
        if png:  # a top view along the up axis, in metres
            files["png"] = out / f"{scene_id}.png"
            write_top_view(files["png"], seg.frame, colors[seg.segmented], f"{scene_id}: {len(seg.scores)} instances")
        row: dict = {"scene": scene_id, "points": len(coord), "instances": int(len(seg.scores)),
                     "seconds": round(seconds, 2), **{k: str(p) for k, p in files.items()},
                     "files": [str(p) for p in files.values()]}
        sample = scan.sample
        if sample is not None and (sample.instance >= 0).any():
            m = summarize([match_scene(sample.instance, seg.masks, seg.scores, valid=sample.valid, scene_id=scene_id)])
            row.update({k: round(m[k], 4) for k in ("AP", "AP50", "AP25", "AR")})
        yield row
