"""CLI: ``assist3d view`` (one self-contained HTML 3D viewer of a scene, a scan or a segmentation)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import typer

from ..core.bounds import MAX_SEED
from ..core.errors import shown


def register(app: typer.Typer) -> None:
    app.command("view")(view_cmd)


def default_html_path(path: str, name: str) -> Path:
    """Where ``view`` writes without ``--out``: beside a scan or segmentation file (its name with
    ``.html``); beside a dataset folder, never into it (``<dataset>_<scene>.html``); else
    ``<scene>.html`` in the working folder (``FORMAT:PATH``)."""
    from ..export.preview import beside_dataset

    p = Path(path)
    if p.is_file():
        return p.with_suffix(".html")
    if p.is_dir():
        return beside_dataset(p, name, ".html")
    return Path(f"{name}.html")


def view_cmd(
    path: str = typer.Argument(..., metavar="PATH", help="a generated scene or dataset folder, a .ply or (N, 3|6|8) .npy "
                               "scan, FORMAT:PATH, or a segmentation .npz of `assist3d segment` (its .ply beside it "
                               "gives the points) or a folder of them"),
    pred: Optional[Path] = typer.Option(None, "--pred", help="a prediction .npz (masks, scores) over PATH's points, "
                                        "e.g. <scene>.npz of `assist3d segment` or `assist3d predict`"),
    scene: Optional[str] = typer.Option(None, "--scene", help="the scene of a dataset folder or FORMAT:PATH "
                                        "(default: the first)"),
    out: Optional[Path] = typer.Option(None, "--out", "-o", help="HTML file to write (default: beside PATH, "
                                       "never inside a dataset folder; see docs/ecosystem.md)"),
    color: Optional[str] = typer.Option(None, "--color", help="colouring the page opens with: rgb, instance, class "
                                        "or prediction (default: instance where there is ground truth, else "
                                        "prediction, else rgb); the page switches between them"),
    side_by_side: bool = typer.Option(False, "--side-by-side", help="open with ground truth and prediction side by "
                                      "side (needs both)"),
    max_points: int = typer.Option(300_000, "--max-points", min=0, max=20_000_000,
                                   help="draw at most this many points (a seeded random draw; 0 = all)"),
    point_size: float = typer.Option(2.0, "--point-size", min=0.5, max=20.0, help="marker size in pixels"),
    seed: int = typer.Option(0, "--seed", min=0, max=MAX_SEED, help="seed of the --max-points draw"),
    as_json: bool = typer.Option(False, "--json", help="print one JSON object: html, points, colors"),
) -> None:
    """Write one HTML file that shows a scene, scan or segmentation in 3D: colour by RGB / instance / class /
    prediction, ground truth and prediction side by side, hover a point for its instance and class. The
    file holds plotly.js and the points: it opens offline in any browser. Needs the \\[view] extra."""
    # (the backslash keeps the rich help from reading "[view]" as a markup tag and dropping it)
    from ..view import available_colors, load_view, plotly_js, subsample, write_viewer

    plotly_js()  # the extra is there, before reading a large scan
    data = subsample(load_view(path, pred=pred, scene=scene), max_points, seed)
    target = out or default_html_path(path, data.name)
    write_viewer(target, data, color=color, side_by_side=side_by_side, point_size=point_size)
    if as_json:
        typer.echo(json.dumps({"html": str(target), "scene": data.name, "points": len(data),
                               "colors": list(available_colors(data)), "bytes": target.stat().st_size}))
        return
    typer.echo(f"wrote {shown(target, 400)} ({len(data):,} points of {shown(data.name)}; colour by "
               f"{', '.join(available_colors(data))}; {target.stat().st_size / 1e6:.1f} MB, opens offline)")
