"""CLI: ``assist3d probe`` (data-quality benchmark on real scans) and ``assist3d segment`` (instances of
any scan with the shipped model, a trained checkpoint or the geometric reference)."""

from __future__ import annotations

import importlib.util
import json
import logging
from pathlib import Path
from typing import Optional

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..config.files import read_yaml_mapping
from ..core.errors import ConfigError, shown

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
    return read_yaml_mapping(config, missing="--config: file not found")


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
    m = result.machine
    table = Table(title=f"bench-train: {', '.join(data)}",
                  caption=f"{m['gpu'] or m['cpu']}, {m['cores']} cores, torch {m['torch']}, "
                          f"native bfloat16 {'yes' if m['native_bfloat16'] else 'no'}")
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
    weight: Optional[list[float]] = typer.Option(None, "--weight", help="one per --train, in order: draw that set's "
                                                 "scenes W times as often as a scene of weight 1 (the paper's real + "
                                                 "0.5 x synthetic: --weight 1 --weight 0.5); default all 1"),
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
    hybrid: bool = typer.Option(False, "--hybrid", help="also score hybrid inference (`assist3d segment "
                                "--method hybrid`) with every seed's model: JSON key 'hybrid' (runs, mean, std); adds "
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
                       max_train_scenes=max_train_scenes, weights=tuple(weight or ()))
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
                              f"{info['train_seconds'] / 60:.1f} min"
                              + (f", {info['precision']}" if info.get("precision") else "")
                              + f"{', cached' if info.get('cached') else ''})")

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
    for col in ("seed", "AP", "AP50 [95% CI]", "AP25", "AR", "steps", "minutes", "precision"):
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
                          str(r["steps"]), f"{r['train_seconds'] / 60:.1f}", r.get("precision") or "-")
        m, s = part["mean"], part["std"]
        table.add_row(f"mean ± std{label}", *(f"{_fmt(m[k])} ± {_fmt(s[k])}" for k in ("AP", "AP50", "AP25", "AR")),
                      f"{m['steps']:.0f}" if m["steps"] is not None else "-", "", "")
    Console().print(table)


# ----------------------------------------------------------------------------------------------- segment

def segment_cmd(
    input_: str = typer.Argument(..., metavar="INPUT", help="a .ply (mesh or point cloud), an (N, 3|6|8) .npy, or FORMAT:PATH"),
    out: Path = typer.Option(..., "--out", "-o", help="output folder: <scene_id>.npz (masks, scores) and <scene_id>.ply "
                             "(points coloured by instance, with an 'instance' vertex property)"),
    checkpoint: Optional[list[Path]] = typer.Option(None, "--checkpoint", help="a trained segmenter (default: the shipped "
                                                    "model); repeat it to average several models' outputs (an ensemble)"),
    method: str = typer.Option("learned", "--method", help="learned (the model's instances, the default), "
                               "hybrid (the model's instances and the geometric components, ranked by the model, "
                               "fallback proposals below them, snapped to superpoints) or "
                               "geometric (planes removed, connected components; no model)"),
    tta: bool = typer.Option(False, "--tta", help="average the network over 8 turned and mirrored copies of the scan "
                             "(8x the network's time; off by default: it helped hybrid inference on 821-step models and lowered the "
                             "network alone on the 2,000-step model v2, docs/results.md)"),
    png: bool = typer.Option(False, "--png", help="also write <scene_id>.png, a top view coloured by instance"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON line per scene (instances, seconds, the files "
                                 "written, AP when GT is known)"),
    threads: int = typer.Option(0, "--threads", min=0, max=256, help="torch CPU threads (0 = all cores)"),
    up_axis: str = typer.Option("z", "--up-axis", help="the scan's up axis: z (ScanNet, ScanNet++, S3DIS), y (many "
                                "mesh exports), -y, x, -x or -z; the scan is turned to z up for the model; the masks, "
                                "npz and PLY keep the input's coordinates, the PNG is the top view in metres"),
    units: str = typer.Option("m", "--units", help="the scan's length unit: m, cm or mm"),
) -> None:
    """Segment object instances in a scan (class-agnostic), with no GPU and no download."""
    from ..learn.segmenter.features import UNITS, UP_AXES

    if up_axis not in UP_AXES:
        raise ConfigError(f"--up-axis {up_axis!r}: expected one of {', '.join(UP_AXES)}")
    if units not in UNITS:
        raise ConfigError(f"--units {units!r}: expected one of {', '.join(UNITS)}")
    _require_torch()
    import torch

    from ..learn.segmenter.predictor import Predictor, segment_scan

    if threads:
        torch.set_num_threads(threads)
    predictor = Predictor.load(list(checkpoint) if checkpoint else None, method=method, tta=tta)
    for row in segment_scan(input_, out, predictor, png=png, up_axis=up_axis, units=units):
        if as_json:
            typer.echo(json.dumps(row))
        else:
            extra = "".join(f"  {k} {row[k]:.3f}" for k in ("AP", "AP50", "AP25") if k in row)
            typer.echo(f"{shown(row['scene'])}: {row['instances']} instances in {row['seconds']:.1f} s{extra} -> "
                       + ", ".join(shown(f, 400) for f in row["files"]))
