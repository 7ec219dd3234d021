"""CLI commands: `assist3d layout` (one scene's layout) and `assist3d layout-png` (top-down picture)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from ..core.bounds import MAX_SCENE_INDEX, MAX_SEED
from ..core.contracts import SceneLayout
from ..core import reading
from ..core.errors import DataError, shown
from ..core.fileio import write_json_atomic
from ..config.presets import compose


def register(app: typer.Typer) -> None:
    app.command("layout")(layout_cmd)
    app.command("layout-png")(layout_png_cmd)


def layout_cmd(
    assets: Optional[str] = typer.Option(None, "--assets", help="Asset catalog folder (default: $ASSIST3D_ASSETS, "
                                                                "the default catalog, or the built-in procedural "
                                                                "library)."),
    seed: int = typer.Option(0, "--seed", min=0, max=MAX_SEED,
                             help="Scene seed, 0..2^32-1: the same seed gives the same layout."),
    out: Path = typer.Option(..., "--out", help="Output folder for layout.json, scene.glb (and layout.png)."),
    png: bool = typer.Option(False, "--png", help="Also write a top-down picture layout.png."),
    config: Optional[Path] = typer.Option(None, "--config", help="YAML config file (see `assist3d generate`)."),
    preset: Optional[str] = typer.Option(None, "--preset", help="Generator preset: assist3d, randomrooms, "
                                                                "holodeck-style, no-context, ablations..."),
    scene_index: int = typer.Option(0, "--scene-index", min=0, max=MAX_SCENE_INDEX,
                                    help="Index of the scene in a dataset (picks the random or complementary "
                                         "selection strategy)."),
    llm_base_url: Optional[str] = typer.Option(None, "--llm-base-url", help="OpenAI-compatible endpoint for the "
                                                                           "LLM relation planner."),
    llm_model: Optional[str] = typer.Option(None, "--llm-model", help="Model name for --llm-base-url."),
    no_glb: bool = typer.Option(False, "--no-glb", help="Skip writing scene.glb."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as one JSON object."),
) -> None:
    """Build one scene's layout (no rendering): layout.json and scene.glb."""
    from ..assets import open_catalog_for
    from ..scene.layout import build_layout, layout_summary

    overrides: dict = {}
    if assets is not None:
        overrides.setdefault("assets", {})["library"] = assets
    if llm_base_url is not None:
        overrides.setdefault("llm", {})["base_url"] = llm_base_url
    if llm_model is not None:
        overrides.setdefault("llm", {})["model"] = llm_model
    cfg = compose(config, preset, overrides)
    catalog = open_catalog_for(cfg.assets)
    layout = build_layout(catalog, cfg, seed, scene_index=scene_index)
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / "layout.json", layout.to_json())
    if not no_glb:
        from ..export.glb import export_glb

        export_glb(layout, catalog, out / "scene.glb")
    if png:
        from ..export.topdown import render_topdown

        render_topdown(layout, catalog, out / "layout.png", title=f"seed {seed} ({cfg.preset})")
    s = layout_summary(layout)
    if as_json:
        typer.echo(json.dumps({**s, "out": str(out), "planner": sorted(set(layout.planner.values()))}))
        return
    p = s["placed"]
    typer.echo(f"layout seed {seed}: {s['instances']} placed (floor {p['floor']}, wall {p['wall']}, "
               f"on-top {p['obj']}), {s['dropped']} dropped, {s['seconds']:.2f} s -> {out}")


def _check_finite(layout, path: Path) -> None:
    """Refuse a layout whose room or poses hold NaN or infinite numbers (a damaged or edited file)."""
    room = np.asarray(layout.room.polygon, dtype=float)
    if not (np.isfinite(room).all() and np.isfinite(layout.room.height)):
        raise DataError(f"{path}: the room polygon or height is not finite (NaN or infinite)")
    for inst in layout.instances:
        if not np.isfinite(np.asarray(inst.pose, dtype=float)).all():
            raise DataError(f"{path}: instance {shown(inst.id, 80)} has a non-finite pose (NaN or infinite)")


def layout_png_cmd(
    layout_json: Path = typer.Argument(..., help="A layout.json written by `assist3d layout` or `generate`."),
    assets: Optional[str] = typer.Option(None, "--assets", help="Asset catalog the layout was built from."),
    out: Path = typer.Option(..., "--out", help="PNG file to write."),
    title: Optional[str] = typer.Option(None, "--title", help="Title of the picture (default: the seed)."),
) -> None:
    """Render a top-down picture of an existing layout."""
    from ..assets import open_catalog
    from ..export.topdown import render_topdown

    data = reading.read_json(layout_json, missing="layout file not found", what="layout")
    try:
        layout = SceneLayout.from_json(data)
    except (KeyError, TypeError, ValueError, AttributeError, IndexError) as e:
        raise DataError(f"{layout_json}: not a readable layout.json ({type(e).__name__}: {shown(e)})") from None
    _check_finite(layout, layout_json)
    catalog = open_catalog(assets)
    render_topdown(layout, catalog, out, title=title)
    typer.echo(f"wrote {out}")
