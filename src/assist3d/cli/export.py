"""CLI: ``assist3d export FORMAT ...``: a generated dataset in other file formats and other projects'
layouts (``export ply``, ``export scannet``, ``export s3dis``; docs/ecosystem.md)."""

from __future__ import annotations

import json
import logging
import sys
from pathlib import Path
from typing import List, Optional

import typer

from ..core.bounds import MAX_WORKERS
from ..core.errors import shown

log = logging.getLogger("assist3d.cli.export")

export_app = typer.Typer(help="Write a generated dataset in other file formats and other projects' layouts, one "
                         "subcommand per format (docs/ecosystem.md).", no_args_is_help=True)


def register(app: typer.Typer) -> None:
    app.add_typer(export_app, name="export")


@export_app.command("scannet")
def export_scannet_cmd(
    data: Path = typer.Argument(..., help="A dataset folder written by 'assist3d generate'."),
    out: Path = typer.Argument(..., help="Output folder: scans/scene<NNNN>_<NN>/, the label map, the split lists."),
    workers: int = typer.Option(1, "--workers", "-w", min=1, max=MAX_WORKERS,
                                help="Scenes exported at once (processes); about 10 s per scene each."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON only."),
) -> None:
    """Every finished scene as a ScanNet v2 scan (mesh PLY, segments, aggregation, labels PLY), with a
    scannetv2-labels.combined.tsv and scannetv2_{train,val,test}.txt, for ScanNet preprocessing scripts."""
    from ..interop.scannet import export_scannet

    def on_scene(scene_id: str, name: str) -> None:
        if not as_json:
            typer.echo(f"{scene_id} -> {out / 'scans' / name}", err=True)

    res = export_scannet(data, out, workers=workers, on_scene=on_scene)
    sys.stdout.write(json.dumps(res) + "\n")


@export_app.command("s3dis")
def export_s3dis_cmd(
    data: Path = typer.Argument(..., help="A dataset folder written by 'assist3d generate'."),
    out: Path = typer.Argument(..., help="Output folder: Area_1/ (train) and Area_5/ (val) rooms."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON only."),
) -> None:
    """Every finished scene as an S3DIS room: Annotations/<class>_<k>.txt per object and surface, and
    Area_N_alignmentAngle.txt, for S3DIS preprocessing scripts."""
    from ..interop.s3dis import export_s3dis

    def on_scene(scene_id: str, folder: str) -> None:
        if not as_json:
            typer.echo(f"{scene_id} -> {folder}", err=True)

    res = export_s3dis(data, out, on_scene=on_scene)
    sys.stdout.write(json.dumps(res) + "\n")


@export_app.command("ply")
def export_ply_cmd(
    data: Path = typer.Argument(..., metavar="DATA", help="a dataset folder of `assist3d generate` (or one scene folder)"),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="write <scene>.ply files into this folder, the "
                                       "dataset untouched (default: points.ply inside each scene folder, as "
                                       "`generate --ply` writes it)"),
    color_by: str = typer.Option("instance", "--color-by", help="instance (a colour per instance, grey background) "
                                 "or rgb (the rendered colours; needs --out)"),
    scene: Optional[List[str]] = typer.Option(None, "--scene", help="only this scene id (repeatable)"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object: written, kept, skipped"),
) -> None:
    """Every scene of a dataset as a binary PLY (x y z, red green blue, instance and segment per point),
    for MeshLab, CloudCompare, Open3D or Blender."""
    from ..pipeline.exports import export_dataset_ply

    run = export_dataset_ply(data, out, color_by=color_by, only=list(scene) if scene else None)
    for name, why in run.skipped.items():
        log.warning("%s skipped: %s", shown(name), why)
    if as_json:
        typer.echo(json.dumps({"written": run.written, "kept": run.kept, "skipped": run.skipped}))
    else:
        where = shown(out, 400) if out is not None else f"points.ply in the scene folders of {shown(data, 400)}"
        typer.echo(f"export ply: {len(run.written)} written, {len(run.kept)} kept (there already), "
                   f"{len(run.skipped)} skipped -> {where}")
    if run.skipped:
        raise typer.Exit(1)
