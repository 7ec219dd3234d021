"""CLI: `assist3d evaluate` (class-agnostic AP/AR, ScanNet rules) and `assist3d convert-predictions`."""

from __future__ import annotations

import importlib
import json
import logging
import math
from pathlib import Path
from typing import Optional

import typer
from rich.console import Console
from rich.progress import Progress
from rich.table import Table

from ..core.bounds import MAX_WORKERS
from ..core.errors import ConfigError, DataError, shown

log = logging.getLogger("assist3d.evaluate")


def register(app: typer.Typer) -> None:
    app.command("evaluate")(evaluate)
    app.command("convert-predictions")(convert_predictions_cmd)


def _load_feature(spec: str):
    """``module:function`` -> the callable (a shape-feature extractor for --ood-reference)."""
    mod_name, _, fn_name = spec.partition(":")
    if not mod_name or not fn_name:
        raise ConfigError(f"--feature {spec!r}: expected MODULE:FUNCTION, e.g. assist3d.bench.evaluation.ood:default_feature")
    try:
        fn = getattr(importlib.import_module(mod_name), fn_name)
    except (ImportError, AttributeError) as e:
        raise ConfigError(f"--feature {spec!r}: cannot import ({e})") from None
    if not callable(fn):
        raise ConfigError(f"--feature {spec!r}: {fn_name} is not callable")
    return fn


def evaluate(
    gt: str = typer.Option(..., "--gt", help="Ground truth as FORMAT:PATH[?options] (scannet, scannetpp, s3dis, "
                                             "pointcept, assist3d, array)."),
    pred: Path = typer.Option(..., "--pred", help="Folder with one <scene_id>.npz (masks, scores) or benchmark "
                                                  "<scene_id>.txt per scene."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object {AP, AP50, AP25, AR, AR50, AR25, scenes, ...}."),
    per_scene: bool = typer.Option(False, "--per-scene", help="Also show (or, with --json, include) each scene's figures."),
    allow_missing: bool = typer.Option(False, "--allow-missing", help="Count scenes without a prediction file as "
                                                                       "scenes with no predictions instead of failing."),
    ood_reference: Optional[str] = typer.Option(None, "--ood-reference", help="Reference dataset FORMAT:PATH (the paper: "
                                                                             "ScanNet v2) for out-of-domain AR."),
    feature: Optional[str] = typer.Option(None, "--feature", help="Shape feature for --ood-reference as MODULE:FUNCTION "
                                                                  "taking (n, 3) points (default: assist3d's shape descriptor). "
                                                                  "This imports and runs that Python code: name only "
                                                                  "modules you trust."),
    workers: int = typer.Option(1, "--workers", "-w", min=1, max=MAX_WORKERS,
                                help=f"Read and match scenes in this many processes (at most {MAX_WORKERS})."),
) -> None:
    """Score instance predictions class-agnostically, exactly like the ScanNet benchmark script."""
    from ..data import open_dataset
    from ..bench.evaluation import METRIC_KEYS, default_feature, evaluate_dataset

    dataset = open_dataset(gt)
    reference = open_dataset(ood_reference) if ood_reference else None
    fn = _load_feature(feature) if feature else default_feature
    err = Console(stderr=True)
    with Progress(console=err, transient=True, disable=as_json) as bar:
        task = bar.add_task(f"evaluating {shown(dataset.name, markup=True)}", total=len(dataset))
        result = evaluate_dataset(
            dataset, pred, allow_missing=allow_missing, ood_reference=reference, feature=fn,
            progress=lambda i, n: bar.update(task, completed=i), workers=workers,
        )
    if as_json:
        typer.echo(json.dumps(result.to_dict(per_scene=per_scene)))
        return

    def pct(x: float) -> str:
        return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{100 * x:.1f}"

    out = Console()
    title = (f"Class-agnostic instance segmentation on {dataset.format}:{shown(dataset.root, 400, markup=True)} "
             f"({len(dataset)} scenes)")
    t = Table(title=title)
    t.add_column("scene" if per_scene else "", justify="left", no_wrap=True)
    for k in METRIC_KEYS:
        t.add_column(k, justify="right")
    t.add_column("GT", justify="right")
    t.add_column("pred", justify="right")
    if per_scene:
        for sid, m in result.per_scene.items():
            t.add_row(shown(sid, markup=True), *(pct(m[k]) for k in METRIC_KEYS), str(m.num_gt), str(m.num_pred))
        t.add_section()
    o = result.overall
    t.add_row("all (pooled)", *(pct(o[k]) for k in METRIC_KEYS), str(o.num_gt), str(o.num_pred), style="bold")
    if result.ood is not None:
        q = result.ood
        t.add_row("out-of-domain", "", "", "", pct(q["AR"]), pct(q["AR50"]), pct(q["AR25"]), str(q.num_gt), "")
    out.print(t)
    out.print("AP/AR: mean over IoU 0.50..0.90 (step 0.05); values in %. Missing prediction files: "
              f"{len(result.missing)}.")


def convert_predictions_cmd(
    src: Path = typer.Argument(..., help="Folder of predictions to convert."),
    dst: Path = typer.Argument(..., help="Output folder."),
    to: str = typer.Option(..., "--to", help="'txt' (ScanNet benchmark text format) or 'npz' (assist3d format)."),
    label_id: int = typer.Option(39, "--label-id", min=0, max=2**31 - 1,
                                 help="with --to txt: the class id written with every mask (default 39, "
                                      "'otherfurniture', an object class the ScanNet benchmark script scores; "
                                      "1 is 'wall', which it drops)"),
) -> None:
    """Convert prediction folders between the assist3d .npz format and the ScanNet benchmark text format."""
    from ..bench.evaluation import convert_predictions
    from ..bench.evaluation.predictions import SCANNET_INSTANCE_IDS

    if to not in ("txt", "npz"):
        raise ConfigError(f"--to {to!r}: expected 'txt' or 'npz'")
    if not src.is_dir():
        raise DataError(f"{shown(src, 400)}: prediction folder not found" + (" (it is a file)" if src.exists() else ""))
    if to == "txt" and label_id not in SCANNET_INSTANCE_IDS:
        log.warning("--label-id %d is not one of the classes the ScanNet benchmark script scores (%s): that "
                    "script will drop these predictions", label_id, ", ".join(map(str, sorted(SCANNET_INSTANCE_IDS))))
    n = convert_predictions(src, dst, to=to, label_id=label_id)
    typer.echo(json.dumps({"scenes": n, "to": to, "out": str(dst), "label_id": label_id if to == "txt" else None}))
