"""CLI: ``assist3d export FORMAT DATA``: a generated dataset in other file formats (``export ply``)."""

from __future__ import annotations

import json
import logging
from pathlib import Path
from typing import List, Optional

import typer

from ..core.errors import shown

log = logging.getLogger("assist3d.cli.export")

export_app = typer.Typer(help="Write a generated dataset in other file formats, one subcommand per format.",
                         no_args_is_help=True)


def register(app: typer.Typer) -> None:
    app.add_typer(export_app, name="export")


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
