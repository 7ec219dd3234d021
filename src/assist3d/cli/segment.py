"""CLI: ``assist3d probe`` (data-quality benchmark on real scans) and ``assist3d segment`` (instances of
any scan with the shipped model, a trained checkpoint or the geometric reference)."""

from __future__ import annotations

import importlib.util
import io
import json
import logging
import time
from pathlib import Path
from typing import Optional

import numpy as np
import typer
import yaml
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..core.errors import ConfigError, DataError, shown
from ..core.fileio import write_bytes_atomic
from ..core.paths import safe_name

log = logging.getLogger("assist3d.segment")


def _require_torch() -> None:
    if importlib.util.find_spec("torch") is None:
        raise ConfigError("this command needs PyTorch: install the [train] extra (pip install 'assist3d[train]')")


def register(app: typer.Typer) -> None:
    app.command("probe")(probe_cmd)
    app.command("segment")(segment_cmd)
    app.command("bench-train")(bench_train_cmd)


def _segmenter_config(config: Optional[Path]) -> dict:
    """The mapping of a ``--config`` YAML file ({} without one); one clear line when it is not one."""
    if config is None:
        return {}
    if not config.is_file():
        raise ConfigError(f"--config {config}: file not found")
    try:
        data = yaml.safe_load(config.read_text()) or {}
    except yaml.YAMLError as e:
        raise ConfigError(f"--config {config}: not valid YAML ({e})") from None
    if not isinstance(data, dict):
        raise ConfigError(f"--config {config}: expected a mapping at the top level")
    return data


def bench_train_cmd(
    data: list[str] = typer.Option(..., "--data", help="training scenes FORMAT:PATH (repeatable), e.g. "
                                   "assist3d:demo_out"),
    steps: int = typer.Option(10, "--steps", min=1, max=10_000, help="timed training steps"),
    warmup: int = typer.Option(3, "--warmup", min=0, max=10_000, help="untimed steps first"),
    precision: str = typer.Option("", "--precision", help="override optim.precision: auto, float32 or bfloat16"),
    config: Optional[Path] = typer.Option(None, "--config", "-c", help="segmenter config YAML (net, augment, optim)"),
    max_train_scenes: int = typer.Option(0, "--max-train-scenes", min=0, help="use the first N scenes of each set"),
    threads: int = typer.Option(0, "--threads", min=0, max=256, help="torch CPU threads (0 = all cores)"),
    device: str = typer.Option("cpu", "--device", help="cpu, cuda or auto"),
    loader_workers: int = typer.Option(0, "--loader-workers", min=0, max=64,
                                       help="processes that build examples ahead of each step"),
    as_json: bool = typer.Option(False, "--json", help="print the figures as JSON"),
) -> None:
    """Time the segmenter's training loop (examples, forward, backward, optimiser): seconds per step,
    steps/s and examples/s, on this machine."""
    _require_torch()
    import torch

    from ..learn.engine.train import resolve_device
    from ..learn.segmenter.bench import bench_training
    from ..learn.segmenter.config import parse_segmenter_config
    from ..learn.segmenter.probe import load_training_scenes

    cfg_data = _segmenter_config(config)
    if precision:
        cfg_data = {**cfg_data, "optim": {**(cfg_data.get("optim") or {}), "precision": precision}}
    cfg = parse_segmenter_config(cfg_data, str(config or "--precision"))
    if threads:
        torch.set_num_threads(threads)
    scenes = load_training_scenes(data, max_train_scenes)
    result = bench_training(scenes, cfg, steps=steps, warmup=warmup, device=resolve_device(device),
                            loader_workers=loader_workers)
    if as_json:
        typer.echo(json.dumps(result.as_dict(), indent=1))
        return
    table = Table(title=f"bench-train: {', '.join(data)}")
    for col in ("device", "precision", "threads", "s/step (median, min-max)", "steps/s", "examples/s"):
        table.add_column(col, justify="right")
    table.add_row(result.device, result.precision, str(result.threads),
                  f"{result.step_s_median:.3f} ({result.step_s_min:.3f}-{result.step_s_max:.3f})",
                  f"{result.steps_per_s:.3f}", f"{result.examples_per_s:.3f}")
    Console().print(table)


def _fmt(x: float | None) -> str:
    return "-" if x is None else f"{x:.3f}"


def probe_cmd(
    train: list[str] = typer.Option(..., "--train", help="training set FORMAT:PATH (repeatable; all are pooled)"),
    eval_: list[str] = typer.Option(..., "--eval", help="real scans FORMAT:PATH to segment zero-shot (repeatable)"),
    minutes: Optional[float] = typer.Option(None, "--minutes", help="training budget per seed in minutes"),
    steps: Optional[int] = typer.Option(None, "--steps", help="training budget per seed in steps (deterministic)"),
    seeds: int = typer.Option(1, "--seeds", min=1, max=100, help="repeat with seeds 0..K-1; report mean and std"),
    first_seed: int = typer.Option(0, "--first-seed", min=0,
                                   help="start the seeds at S (seeds S..S+K-1): to split one probe over "
                                        "processes or machines, each writing its seed_K folders"),
    out: Path = typer.Option(Path("probe_out"), "--out", "-o", help="resumable output folder"),
    config: Optional[Path] = typer.Option(None, "--config", "-c", help="segmenter config YAML (net, augment, cluster, optim)"),
    max_train_scenes: int = typer.Option(0, "--max-train-scenes", min=0, help="use the first N scenes of each training set (0 = all)"),
    as_json: bool = typer.Option(False, "--json", help="print the summary as JSON (runs, mean, std)"),
    threads: int = typer.Option(0, "--threads", min=0, max=256, help="torch CPU threads (0 = all cores)"),
    device: str = typer.Option("cpu", "--device", help="where the network trains: cpu, cuda or auto (cuda when "
                               "available); the budget in --steps gives the same recipe on either"),
    loader_workers: int = typer.Option(0, "--loader-workers", min=0, max=64,
                                       help="processes that build training examples ahead of each step "
                                            "(same batches for any number; 1 helps on 2 cores, more on a GPU machine)"),
    jobs: int = typer.Option(1, "--jobs", min=1, max=64, help="train up to N seeds at once, each in its own "
                             "process (for a GPU machine; each process loads its own copy of the training scenes)"),
    hybrid: bool = typer.Option(False, "--hybrid", help="also score hybrid inference (the default of `assist3d "
                                "segment`) with every seed's model: JSON key 'hybrid' (runs, mean, std); adds "
                                "it to a finished folder without retraining"),
) -> None:
    """Train the CPU segmenter on TRAIN for a fixed budget, segment EVAL zero-shot, print AP/AP50/AP25/AR
    of the network's instances (and with --hybrid of hybrid inference too)."""
    _require_torch()
    import torch

    from ..learn.segmenter.config import parse_segmenter_config
    from ..learn.segmenter.probe import ProbeRequest, die_with_parent, run_probe, run_probe_jobs
    from ..learn.engine.train import resolve_device
    from ..learn.segmenter.train import Budget

    die_with_parent()  # a seed process of --jobs: stops with the probe that started it
    if minutes is None and steps is None:
        minutes = 50.0
    cfg_data = _segmenter_config(config)
    req = ProbeRequest(train=tuple(train), eval=tuple(eval_), budget=Budget(steps=steps, minutes=minutes),
                       seeds=seeds, config=parse_segmenter_config(cfg_data, str(config or "defaults")),
                       max_train_scenes=max_train_scenes)
    if threads:
        torch.set_num_threads(threads)
    console = Console(stderr=True)
    total = steps if steps is not None else None
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(), TextColumn("{task.fields[info]}"),
                  TimeElapsedColumn(), console=console, disable=as_json and not console.is_terminal) as bar:
        task = bar.add_task("probe", total=None, info="")

        def on_event(kind: str, info: dict) -> None:
            if kind == "load":
                bar.update(task, description="load", total=info["total"], completed=info["done"], info="training scenes")
            elif kind == "train_start":
                bar.update(task, description=f"train seed {info['seed']}", completed=0,
                           total=total if total else 100.0, info="")
            elif kind == "step":
                done = info["step"] if total else min(100.0, 100.0 * info["progress"])
                bar.update(task, completed=done, info=f"step {info['step']} loss {info['loss']:.3f} "
                                                      f"({info['train_seconds'] / 60:.1f} min)")
            elif kind == "eval":
                bar.update(task, description=f"eval seed {info['seed']}" + (f" ({info['method']})" if "method" in info
                                                                             else ""),
                           total=info["total"], completed=info["done"], info="")
            elif kind == "job_start":
                bar.update(task, description=f"{info['running']} seeds training at once", info=f"seed {info['seed']} started")
            elif kind == "job_done":
                bar.update(task, total=info["total"], completed=info["done"],
                           info=f"seed {info['seed']} " + ("done" if info["returncode"] == 0 else "FAILED"))
            elif kind == "seed_done":
                h = info.get("hybrid") if hybrid else None
                console.print(f"seed {info['seed']}: AP {_fmt(info['AP'])}  AP50 {_fmt(info['AP50'])}  "
                              f"AP25 {_fmt(info['AP25'])}  AR {_fmt(info['AR'])}"
                              + (f"  hybrid AP50 {_fmt(h['AP50'])}" if h else "")
                              + f"  ({info['steps']} steps, "
                              f"{info['train_seconds'] / 60:.1f} min{', cached' if info.get('cached') else ''})")

        if jobs > 1:
            summary = run_probe_jobs(req, out, jobs=jobs, device=resolve_device(device), loader_workers=loader_workers,
                                     hybrid=hybrid, first_seed=first_seed, threads=threads, on_event=on_event)
        else:
            summary = run_probe(req, out, device=resolve_device(device), loader_workers=loader_workers,
                                hybrid=hybrid, first_seed=first_seed, on_event=on_event)
    if as_json:
        typer.echo(json.dumps({k: summary[k] for k in ("runs", "mean", "std", "hybrid") if k in summary}, indent=1))
        return
    table = Table(title=f"probe: {', '.join(train)} -> {', '.join(eval_)}")
    for col in ("seed", "AP", "AP50 [95% CI]", "AP25", "AR", "steps", "minutes"):
        table.add_column(col, justify="right")
    for label, part in (("", summary), (" hybrid", summary.get("hybrid"))):
        if part is None:
            continue
        if label:
            table.add_section()
        for r in part["runs"]:
            ci = r.get("ci95", {}).get("AP50")
            ci_s = f" [{ci[0]:.3f}, {ci[1]:.3f}]" if ci else ""
            table.add_row(f"{r['seed']}{label}", _fmt(r["AP"]), _fmt(r["AP50"]) + ci_s, _fmt(r["AP25"]), _fmt(r["AR"]),
                          str(r["steps"]), f"{r['train_seconds'] / 60:.1f}")
        m, s = part["mean"], part["std"]
        table.add_row(f"mean ± std{label}", *(f"{_fmt(m[k])} ± {_fmt(s[k])}" for k in ("AP", "AP50", "AP25", "AR")),
                      f"{m['steps']:.0f}" if m["steps"] is not None else "-", "")
    Console().print(table)


# ----------------------------------------------------------------------------------------------- segment

def _scan_from_file(path: Path) -> tuple[str, np.ndarray, np.ndarray | None, object | None]:
    """(scene_id, coord (N, 3) float32, color (N, 3) uint8 or None, PointSample with GT or None) from
    .ply / .npy, N > 0. Raw points (a .ply, an (N, 3|6) .npy) may hold non-finite coordinates:
    :func:`usable_points` picks the ones to segment. An (N, 8) .npy is read by the ``array``
    reader and follows its rules."""
    from ..bench.data.base import REAL_KINDS, clean_colors, read_npy
    from ..bench.data.ply import read_ply

    if not path.is_file():
        raise DataError(f"{path}: input not found" + (" (it is a folder: give FORMAT:PATH)" if path.is_dir() else ""))
    suffix = path.suffix.lower()
    if suffix == ".ply":
        mesh = read_ply(path)
        coord, color = mesh.xyz(), mesh.rgb()
    elif suffix == ".npy":
        a = read_npy(path)
        if a.ndim != 2 or a.shape[1] not in (3, 6, 8) or a.dtype.kind not in REAL_KINDS:
            raise DataError(f"{path}: expected a numeric (N, 3), (N, 6) or (N, 8) array (xyz[, rgb[, semantic, instance]]), "
                            f"got {a.dtype} {a.shape}")
        if a.shape[1] == 8 and len(a):
            from ..bench.data.array import ArrayDataset

            s = ArrayDataset(path).load(path.stem)
            return path.stem, s.coord, s.color, s
        with np.errstate(over="ignore", invalid="ignore"):
            coord = np.ascontiguousarray(a[:, :3], np.float32)
        color = clean_colors(path, a[:, 3:6]) if a.shape[1] >= 6 else None
    else:
        raise DataError(f"{path}: unsupported input {suffix or '(no suffix)'}; give a .ply, an (N, 3|6|8) .npy or FORMAT:PATH")
    if len(coord) == 0:
        raise DataError(f"{path}: scene {shown(path.stem)} has no points")
    return path.stem, coord, color, None


def usable_points(where: str, scene_id: str, coord: np.ndarray, units: str = "m") -> np.ndarray:
    """(N,) bool: the points to segment, those with finite coordinates within ``MAX_COORD_M`` metres
    (``coord`` is in ``units``, so the limit is taken in those units); the others get no instance,
    with one warning giving their count. DataError when none is left."""
    from ..bench.data.base import MAX_COORD_M
    from ..learn.segmenter.features import UNITS

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


def _inputs(spec: str):
    """Yield (scene_id, coord, color, sample-with-GT-or-None) for a file or a reader spec."""
    from ..bench.data import READERS, open_dataset

    if spec.split(":", 1)[0].strip().lower() not in READERS or Path(spec).exists():
        yield _scan_from_file(Path(spec))
        return

    ds = open_dataset(spec)
    for sid in ds.scene_ids:
        s = ds.load(sid)
        yield sid, s.coord, s.color, s


def instance_colors(labels: np.ndarray) -> np.ndarray:
    """A distinct colour per instance, grey for points in none."""
    rng = np.random.default_rng(7)
    k = int(labels.max()) + 1 if len(labels) and labels.max() >= 0 else 0
    pal = (rng.uniform(0.15, 1.0, (max(k, 1), 3)) * 255).astype(np.uint8)
    out = np.full((len(labels), 3), 150, np.uint8)
    sel = labels >= 0
    out[sel] = pal[labels[sel]]
    return out


def _png(path: Path, coord: np.ndarray, colors: np.ndarray, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    order = np.argsort(coord[:, 2])
    fig, ax = plt.subplots(figsize=(7, 7), dpi=110)
    ax.scatter(coord[order, 0], coord[order, 1], c=colors[order] / 255.0, s=1.0, linewidths=0)
    ax.set_aspect("equal")
    ax.set_title(title)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", bbox_inches="tight")
    plt.close(fig)
    write_bytes_atomic(path, buf.getvalue())


def segment_cmd(
    input_: str = typer.Argument(..., metavar="INPUT", help="a .ply (mesh or point cloud), an (N, 3|6|8) .npy, or FORMAT:PATH"),
    out: Path = typer.Option(..., "--out", "-o", help="output folder: <scene_id>.npz (masks, scores) and <scene_id>.ply"),
    checkpoint: Optional[list[Path]] = typer.Option(None, "--checkpoint", help="a trained segmenter (default: the shipped "
                                                    "model); repeat it to average several models' outputs (an ensemble)"),
    method: str = typer.Option("hybrid", "--method", help="hybrid (the model's instances and the geometric components, "
                               "ranked by the model, fallback proposals below them, snapped to superpoints), "
                               "learned (the model's instances only) or "
                               "geometric (planes removed, connected components; no model)"),
    tta: bool = typer.Option(False, "--tta", help="average the network over 8 turned and mirrored copies of the scan "
                             "(8x the network's time; measured in docs/fidelity.md, off by default)"),
    png: bool = typer.Option(False, "--png", help="also write <scene_id>.png, a top view coloured by instance"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON line per scene (instances, seconds, AP when GT is known)"),
    threads: int = typer.Option(0, "--threads", min=0, max=256, help="torch CPU threads (0 = all cores)"),
    up_axis: str = typer.Option("z", "--up-axis", help="the scan's up axis: z (ScanNet, ScanNet++, S3DIS), y (many "
                                "mesh exports), -y, x, -x or -z; the scan is turned to z up for the model; the masks, "
                                "npz and PLY keep the input's coordinates, the PNG is the top view in metres"),
    units: str = typer.Option("m", "--units", help="the scan's length unit: m, cm or mm"),
) -> None:
    """Segment object instances in a scan (class-agnostic), with no GPU and no download."""
    from ..bench.evaluation.ap import match_scene, summarize
    from ..bench.evaluation.predictions import save_predictions
    from ..bench.data.ply import write_ply

    if method not in ("hybrid", "learned", "geometric"):
        raise ConfigError(f"--method {method!r}: expected 'hybrid', 'learned' or 'geometric'")
    if method == "geometric" and checkpoint:
        raise ConfigError("--checkpoint is for --method hybrid or learned; the geometric reference has no weights")
    if method == "geometric" and tta:
        raise ConfigError("--tta is for --method hybrid or learned; the geometric reference has no network to average")
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: exists and is not a folder")
    from ..learn.engine.voxelize import VoxelGridError
    from ..learn.segmenter.features import UNITS, UP_AXES, to_segmenter_frame

    if up_axis not in UP_AXES:
        raise ConfigError(f"--up-axis {up_axis!r}: expected one of {', '.join(UP_AXES)}")
    if units not in UNITS:
        raise ConfigError(f"--units {units!r}: expected one of {', '.join(UNITS)}")
    loaded = None
    if method != "geometric":
        _require_torch()
        import torch

        from ..learn.segmenter.checkpoint import load_segmenters
        from ..learn.segmenter.shipped import shipped_model_path

        if threads:
            torch.set_num_threads(threads)
        loaded = load_segmenters(list(checkpoint or [shipped_model_path()]))
    n_done = 0
    for scene_id, coord, color, sample in _inputs(input_):
        t0 = time.perf_counter()
        safe_name(scene_id, what=f"{input_}: scene id")
        coord = np.asarray(coord, np.float32)
        if len(coord) == 0:
            raise DataError(f"{input_}: scene {shown(scene_id)} has no points")
        finite = usable_points(input_, scene_id, coord, units)
        sub_color = color[finite] if color is not None else None
        frame = to_segmenter_frame(coord[finite], up_axis, units)  # what the model sees: metres, z up
        hint = frame_hint(frame)
        if hint:
            log.warning("%s: scene %s: %s", shown(input_), shown(scene_id), hint)
        try:
            if loaded is not None and method == "hybrid":
                from ..learn.segmenter.hybrid import segment_hybrid

                seg = segment_hybrid(loaded.model, loaded.config, frame, sub_color, tta=tta)
            elif loaded is not None:
                from ..learn.segmenter.infer import segment_points

                seg = segment_points(loaded.model, loaded.config, frame, sub_color, tta=tta)
            else:
                from ..learn.segmenter.geometric import segment_geometric

                seg = segment_geometric(frame)
        except VoxelGridError as e:  # a scan too large for the voxel grid, e.g. millimetres read as metres
            fix = ("give --units mm or cm if it is not in metres" if units == "m"
                   else f"it was read in {units}: check --units")
            raise DataError(f"{input_}: scene {shown(scene_id)}: {e}; {fix}") from None
        masks = np.zeros((len(seg.scores), len(coord)), bool)
        masks[:, finite] = seg.masks
        labels = np.full(len(coord), -1, np.int64)
        labels[finite] = seg.labels
        seconds = time.perf_counter() - t0
        out.mkdir(parents=True, exist_ok=True)
        save_predictions(out / f"{scene_id}.npz", masks, seg.scores)
        colors = instance_colors(labels)
        safe_coord = np.where(finite[:, None], coord, 0).astype(np.float32)
        write_ply(out / f"{scene_id}.ply", safe_coord, colors)
        if png:  # a top view along the up axis, in metres
            _png(out / f"{scene_id}.png", frame, colors[finite], f"{scene_id}: {len(seg.scores)} instances")
        row: dict = {"scene": scene_id, "points": len(coord), "instances": int(len(seg.scores)),
                     "seconds": round(seconds, 2), "npz": str(out / f"{scene_id}.npz")}
        if sample is not None and (sample.instance >= 0).any():
            m = summarize([match_scene(sample.instance, masks, seg.scores, valid=sample.valid, scene_id=scene_id)])
            row.update({k: round(m[k], 4) for k in ("AP", "AP50", "AP25", "AR")})
        n_done += 1
        if as_json:
            typer.echo(json.dumps(row))
        else:
            extra = "".join(f"  {k} {row[k]:.3f}" for k in ("AP", "AP50", "AP25") if k in row)
            typer.echo(f"{shown(scene_id)}: {row['instances']} instances in {row['seconds']:.1f} s{extra} -> "
                       f"{shown(out / scene_id, 400)}.npz, .ply")
