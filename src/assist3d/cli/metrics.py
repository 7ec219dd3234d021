"""CLI: `assist3d metrics` (dataset comparison) and `assist3d cluster-assets` (shape clusters)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import List, Optional

import typer
from rich.console import Console
from rich.table import Table

from ..core.bounds import MAX_SCENES, MAX_SEED
from ..config import LLMConfig
from ..core.errors import shown
from ..core.paths import resolve_library

MAX_CLUSTERS = 1000


def register(app: typer.Typer) -> None:
    app.command("metrics")(metrics)
    app.command("cluster-assets")(cluster_assets_cmd)


def metrics(
    datasets: List[str] = typer.Argument(..., help="Datasets as FORMAT:PATH (scannet, scannetpp, s3dis, pointcept, "
                                                  "assist3d, array); a bare folder means an assist3d dataset."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object {name: {metric: value}}."),
    assets: Optional[str] = typer.Option(None, "--assets", help="Asset catalog of the generated datasets "
                                                                "(default: the one each manifest names)."),
    codebook: Optional[Path] = typer.Option(None, "--codebook", help="Shape codebook to reuse (.npz) so values are "
                                                                     "comparable across runs."),
    save_codebook: Optional[Path] = typer.Option(None, "--save-codebook", help="Write the fitted codebook here."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Also write a PNG of per-dataset distributions."),
    max_scenes: Optional[int] = typer.Option(None, "--max-scenes", min=1, max=MAX_SCENES,
                                             help="Use at most this many scenes per dataset."),
    seed: int = typer.Option(0, "--seed", min=0, max=MAX_SEED, help="Seed of point subsampling, the codebook and the "
                                                                   "scene resampling behind layout_realism_se."),
    llm_base_url: Optional[str] = typer.Option(None, "--llm-base-url", help="Also ask a vision-language model for a "
                                                                           "layout score (OpenAI-compatible)."),
    llm_model: Optional[str] = typer.Option(None, "--llm-model", help="Vision model name for --llm-base-url."),
    realism_reference: Optional[str] = typer.Option(
        None, "--realism-reference", help="Reference of layout_realism: a JSON file from scripts/realism_reference.py "
                                          "or a labelled dataset FORMAT:PATH, whose real scans count every annotated "
                                          "object as generated scans do (?objects=benchmark: the 18 benchmark classes "
                                          "only). Default: the shipped statistics of real ScanNet scans."),
) -> None:
    """Geometry diversity, context complexity and layout reasonability of one or more datasets."""
    from ..bench.metrics.diversity import Codebook
    from ..bench.metrics.realism import load_reference
    from ..bench.metrics.report import (codebook_draws, metrics_table, plot_summaries, realism_hint, shared_codebook,
                                        summarize_dataset)

    vlm_cfg = None
    if llm_base_url and llm_model:
        vlm_cfg = LLMConfig(base_url=llm_base_url, model=llm_model)
    summaries = [summarize_dataset(d, assets=assets, max_scenes=max_scenes, seed=seed, vlm_cfg=vlm_cfg)
                 for d in datasets]
    cb = Codebook.load(codebook) if codebook else shared_codebook(summaries, seed=seed)
    if save_codebook:
        cb.save(save_codebook)
    others = () if codebook else codebook_draws(summaries, seed=seed)  # geometry_diversity_sd
    table = metrics_table(summaries, cb, load_reference(realism_reference, max_scenes=max_scenes), seed=seed,
                          other_codebooks=others)
    if plot:
        plot_summaries(summaries, cb, plot)
    if as_json:
        typer.echo(json.dumps(table))
        return
    t = Table(title="Dataset comparison (geometry diversity up, context complexity down, layout score and realism up)")
    for col in ("dataset", "scenes", "instances", "geometry diversity (± sd)", "context complexity", "layout score",
                "layout realism (± s.e.)"):
        t.add_column(col, justify="right" if col != "dataset" else "left")
    fmt = lambda v, p: "n/a" if v is None else f"{v:.{p}f}"  # noqa: E731
    for name, row in table.items():
        realism = fmt(row["layout_realism"], 1)
        if row["layout_realism_se"] is not None:
            realism += f" ± {row['layout_realism_se']:.1f}"
        geometry = fmt(row["geometry_diversity"], 3)
        if row["geometry_diversity_sd"] is not None:
            geometry += f" ± {row['geometry_diversity_sd']:.3f}"
        t.add_row(shown(name, markup=True), str(row["scenes"]), str(row["instances"]), geometry,
                  fmt(row["context_complexity"], 3), fmt(row["layout_score"], 1), realism)
    Console().print(t)
    for name, row in table.items():
        if row.get("layout_realism_profile"):
            Console(stderr=True).print(f"[dim]{shown(name, markup=True)}: {realism_hint(row)}[/dim]")
        for k, why in (row.get("notes") or {}).items():
            Console(stderr=True).print(f"[dim]{shown(name, markup=True)}: {k} n/a: {shown(why, markup=True)}[/dim]")


def cluster_assets_cmd(
    library: Optional[str] = typer.Option(None, "--library", help="Catalog folder (default: $ASSIST3D_ASSETS or the "
                                                                  "default catalog)."),
    k: int = typer.Option(5, "--k", min=1, max=MAX_CLUSTERS, help=f"Number of shape clusters, 1..{MAX_CLUSTERS} "
                                                                  "(paper: 5)."),
    seed: int = typer.Option(0, "--seed", min=0, max=MAX_SEED, help="Seed of feature sampling and k-means."),
) -> None:
    """Compute per-asset shape features (cached) and k-means shape clusters for the geometry ablation."""
    from ..assets.catalog import Catalog
    from ..bench.metrics.clusters import cluster_assets

    cat = Catalog.open(resolve_library(library))
    sizes = cluster_assets(cat, k=k, seed=seed)
    typer.echo(json.dumps({"library": str(cat.root), "clusters": sizes}))
