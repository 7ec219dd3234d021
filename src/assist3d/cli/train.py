"""CLI commands: train, predict, model-bench (the class-agnostic Mask3D-style model; needs torch)."""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from ..core.bounds import MAX_THREADS
from ..core.errors import ConfigError

MAX_EPOCHS = 100_000
MAX_TOP_K = 10_000
MAX_BENCH_POINTS = 10_000_000  # 100 x the default; the paper's scenes have ~100k-300k points


def _require_torch() -> None:
    if importlib.util.find_spec("torch") is None:
        raise ConfigError("this command needs PyTorch: install the [train] extra (pip install 'assist3d[train]')")


def register(app: typer.Typer) -> None:
    @app.command("train")
    def train_cmd(
        config: Path = typer.Option(..., "--config", "-c", help="training config YAML (presets in configs/)"),
        data: list[str] = typer.Option(None, "--data", help="\\[real=|synthetic=]FORMAT:PATH; replaces the config's "
                                       "training sets (repeatable; assist3d: defaults to synthetic, others to real)"),
        out: Path = typer.Option(Path("runs/train"), "--out", "-o", help="folder for checkpoints and metrics.csv"),
        resume: bool = typer.Option(False, "--resume", help="continue from OUT/last.pt"),
        epochs: int = typer.Option(0, "--epochs", min=0, max=MAX_EPOCHS,
                                   help=f"override optim.epochs (0 = keep; at most {MAX_EPOCHS:,})"),
        device: str = typer.Option("", "--device", help="override device: auto, cpu, cuda"),
    ) -> None:
        """Train the model; writes OUT/last.pt, OUT/epoch_NNNN.pt, OUT/metrics.csv and OUT/config.yaml."""
        _require_torch()

        from ..learn.engine.config import load_train_config, parse_data_arg
        from ..learn.engine.train import train

        cfg = load_train_config(config)
        if data:
            cfg = cfg.model_copy(update={"data": cfg.data.model_copy(update={"train": [parse_data_arg(d) for d in data]})})
        if epochs > 0:
            cfg = cfg.model_copy(update={"optim": cfg.optim.model_copy(update={"epochs": epochs})})
        if device:
            cfg = cfg.model_copy(update={"device": device})
        cfg = type(cfg).model_validate(cfg.model_dump())
        if int(os.environ.get("RANK", "0")) != 0:  # torchrun: only rank 0 talks
            train(cfg, out, resume=resume)
            return
        with Progress(TextColumn("[bold]train"), BarColumn(), TextColumn("{task.completed}/{task.total} steps"),
                      TextColumn("{task.fields[info]}"), TimeElapsedColumn(), TimeRemainingColumn()) as bar:
            task = bar.add_task("train", total=None, info="")

            def on_step(row: dict) -> None:
                bar.update(task, total=row["epochs"] * row["steps_per_epoch"], completed=row["step"],
                           info=f"epoch {row['epoch']} loss {row['loss']:.3f}")

            result = train(cfg, out, resume=resume, on_step=on_step)
        typer.echo(json.dumps({"out": str(result.out_dir), "steps": result.steps, "last_loss": result.last_loss,
                               "checkpoint": str(result.checkpoint), "seconds": round(result.seconds, 1)}))

    @app.command("predict")
    def predict_cmd(
        checkpoint: Path = typer.Option(..., "--checkpoint", help="a *.pt written by `assist3d train`"),
        data: str = typer.Option(..., "--data", help="FORMAT:PATH of the scenes to segment"),
        out: Path = typer.Option(..., "--out", "-o", help="folder for <scene_id>.npz predictions"),
        top_k: int = typer.Option(0, "--top-k", min=0, max=MAX_TOP_K,
                                  help=f"masks kept per scene (0 = the checkpoint config's; at most {MAX_TOP_K:,})"),
        dbscan: bool = typer.Option(None, "--dbscan/--no-dbscan", help="split masks with DBSCAN (default: config)"),
        device: str = typer.Option("auto", "--device", help="auto, cpu or cuda"),
    ) -> None:
        """Write <scene_id>.npz (masks bool [M, N], scores float32 [M]) for every scene; score them with evaluate."""
        _require_torch()
        from ..learn.engine.predict import predict_dataset

        overrides: dict = {}
        if top_k > 0:
            overrides["top_k"] = top_k
        if dbscan is not None:
            overrides["dbscan"] = dbscan
        files = predict_dataset(checkpoint, data, out, device=device, overrides=overrides)
        typer.echo(json.dumps({"out": str(out), "scenes": len(files)}))

    @app.command("model-bench")
    def model_bench_cmd(
        points: int = typer.Option(100_000, "--points", min=1, max=MAX_BENCH_POINTS,
                                   help=f"points in the synthetic scene (at most {MAX_BENCH_POINTS:,})"),
        backend: str = typer.Option("torch", "--backend", help="torch or spconv"),
        device: str = typer.Option("cpu", "--device", help="cpu or cuda"),
        config: Path = typer.Option(None, "--config", help="model config (default: the paper model)"),
        repeats: int = typer.Option(3, "--repeats", min=1, max=1000,
                                    help="timed runs after one warm-up (median reported; at most 1000)"),
        threads: int = typer.Option(0, "--threads", min=0, max=MAX_THREADS,
                                    help="torch CPU threads (0 = the config's, else torch default)"),
        as_json: bool = typer.Option(False, "--json", help="print JSON instead of a table"),
    ) -> None:
        """Forward and forward+backward time and peak memory of the model on one scene."""
        _require_torch()

        from ..learn.engine.bench import run_model_bench
        from ..learn.engine.config import TrainConfig, load_train_config

        if backend not in ("torch", "spconv"):
            raise ConfigError(f"--backend {backend!r}: expected torch or spconv")
        cfg = load_train_config(config) if config is not None else TrainConfig()
        if threads > 0:
            cfg = cfg.model_copy(update={"threads": threads})
        res = run_model_bench(cfg, points=points, backend=backend, device=device, repeats=repeats)
        if as_json:
            typer.echo(json.dumps(res.as_dict()))
            return
        table = Table(title=f"model-bench: {res.points} points, {res.voxels} voxels, {res.backend} on {res.device}")
        table.add_column("pass")
        table.add_column("time (s)", justify="right")
        table.add_column("peak memory (MiB)", justify="right")
        table.add_row("forward", f"{res.forward_s:.3f}", f"{res.forward_peak_mib:.0f}")
        if res.forward_backward_s is not None and res.forward_backward_peak_mib is not None:
            table.add_row("forward+backward", f"{res.forward_backward_s:.3f}", f"{res.forward_backward_peak_mib:.0f}")
        Console().print(table)
        if res.note:
            Console().print(res.note)
