"""CLI: ``assist3d export scannet | s3dis DATA OUT``: a generated dataset in other projects' formats."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import typer

from ..core.bounds import MAX_WORKERS

export_app = typer.Typer(help="Write a generated dataset in other projects' formats (docs/ecosystem.md).",
                         no_args_is_help=True)


@export_app.command("scannet")
def export_scannet_cmd(
    data: Path = typer.Argument(..., help="A dataset folder written by 'assist3d generate'."),
    out: Path = typer.Argument(..., help="Output folder: scans/sceneXXXX_YY/, the label map, the split lists."),
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


def register(app: typer.Typer) -> None:
    app.add_typer(export_app, name="export")
