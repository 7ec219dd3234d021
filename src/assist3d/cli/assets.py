"""``assist3d assets ...``: import real catalogs, build the procedural library, inspect a catalog.

Every command takes ``--library DIR``; without it, ``$ASSIST3D_ASSETS``, else the default folder
(``assist3d.core.paths.default_library``).
"""

from __future__ import annotations

import inspect
import json
import os
import sys
import time
from collections import Counter
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator, List, Optional

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..core.bounds import MAX_SEED, MAX_WORKERS
from ..core.contracts import GROUPS
from ..core.errors import AssetError, ConfigError, shown
from ..core.paths import ENV_ASSETS, resolve_library

LIBRARY_HELP = f"Catalog folder (default: ${ENV_ASSETS}, else <cache>/assets)."
MAX_PROCEDURAL = 100_000  # as AssetsConfig.procedural_count

assets_app = typer.Typer(help="Asset catalogs: import Sweet Home 3D or mesh folders, build the procedural library, stats.",
                         no_args_is_help=True)
import_app = typer.Typer(help="Import real asset collections into a catalog.", no_args_is_help=True)
assets_app.add_typer(import_app, name="import")


def _stderr_console():
    return Console(stderr=True)


@contextmanager
def _progress_bar(label: str, enabled: bool = True) -> Iterator:
    """Yield a ``progress(done, total, name)`` callback drawing a rich progress bar on stderr."""
    if not enabled:
        yield None
        return

    # auto_refresh=False: no refresh thread, so the importers' forked workers never inherit a
    # console lock held by it; the bar is redrawn on each update instead
    with Progress(TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  TextColumn("{task.fields[item]}"), console=_stderr_console(), transient=False,
                  auto_refresh=False) as bar:
        task = bar.add_task(label, total=None, item="")

        def update(done: int, total: int, name: str) -> None:
            bar.update(task, completed=done, total=total, item=shown(name, 40, markup=True))
            bar.refresh()

        yield update


def _print_summary(title: str, report_json: dict, catalog, as_json: bool) -> None:
    stats = catalog.stats().to_json()
    if as_json:
        sys.stdout.write(json.dumps({"import": report_json, "catalog": str(catalog.root), "stats": stats}) + "\n")
        return

    console = Console()
    table = Table(title=title)
    table.add_column("catalog")
    table.add_column("assets", justify="right")
    for name, n in report_json["added"].items():
        table.add_row(shown(name, markup=True), str(n))
    table.add_row("[bold]total", f"[bold]{report_json['total']}")
    console.print(table)
    skipped = report_json["skipped"]
    if skipped:
        sk = Table(title=f"skipped ({len(skipped)})")
        sk.add_column("path", overflow="fold")
        sk.add_column("reason", overflow="fold")
        for s in skipped:
            sk.add_row(shown(s["path"], 400, markup=True), shown(s["reason"], markup=True))
        console.print(sk)
    console.print(f"{report_json['total']} assets imported in {report_json['seconds']:.1f} s into "
                  f"{shown(catalog.root, 400, markup=True)}; "
                  f"catalog now: {stats['assets']} assets, {stats['classes']} classes, groups {stats['groups']}")


def _fail_if_nothing_imported(report_json: dict) -> None:
    """An import that skipped every input is an error (exit 2), with the reasons printed above."""
    skipped = report_json.get("skipped") or []
    if report_json.get("total", 0) == 0 and skipped:
        raise AssetError(f"nothing imported: all {len(skipped)} inputs were skipped (reasons above)")


@import_app.command("sh3d")
def import_sh3d_cmd(
    paths: Optional[List[Path]] = typer.Argument(None, help=".sh3f files, sweethome3d.jar or folders of .sh3f "
                                                          "(default: /usr/share/sweethome3d/furniture/*.sh3f + the jar)."),
    library: Optional[Path] = typer.Option(None, "--library", help=LIBRARY_HELP),
    workers: int = typer.Option(0, "--workers", min=0, max=MAX_WORKERS,
                                help="Worker processes (0 = one per CPU core, 1 = in-process)."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object (import report and stats) instead of tables."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar on stderr."),
) -> None:
    """Import Sweet Home 3D furniture catalogs (re-running replaces the same catalogs' records)."""
    from ..assets.catalog import Catalog
    from ..assets.sh3d import default_sh3d_paths, import_sh3d

    if not paths and not default_sh3d_paths():
        raise AssetError("no Sweet Home 3D catalogs given and none installed; install them with "
                         "`apt-get install sweethome3d sweethome3d-furniture` or pass .sh3f paths")
    root = resolve_library(library)
    catalog = Catalog.open_or_create(root)
    with _progress_bar("sh3d", progress) as update:
        report = import_sh3d(catalog, paths or None, workers=workers or None, progress=update)
    _print_summary("Sweet Home 3D import", report.to_json(), catalog, as_json)
    _fail_if_nothing_imported(report.to_json())


@import_app.command("meshes")
def import_meshes_cmd(
    folder: Path = typer.Argument(..., help="Folder holding the meshes (paths in the manifest are relative to it)."),
    manifest: Path = typer.Option(..., "--manifest", help="CSV or JSON manifest: path, class, groups, size/scale, up, "
                                                          "front, license, attribution (see docs/assets.md)."),
    name: Optional[str] = typer.Option(None, "--name", help="Collection name used in ids (default: the folder name)."),
    library: Optional[Path] = typer.Option(None, "--library", help=LIBRARY_HELP),
    workers: int = typer.Option(0, "--workers", min=0, max=MAX_WORKERS,
                                help="Worker processes (0 = one per CPU core, 1 = in-process)."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object instead of tables."),
    progress: bool = typer.Option(True, "--progress/--no-progress", help="Show a progress bar on stderr."),
) -> None:
    """Import a folder of meshes (OBJ, GLB/GLTF, PLY, STL, OFF) described by a manifest."""
    from ..assets.catalog import Catalog
    from ..assets.meshes import import_meshes

    root = resolve_library(library)
    catalog = Catalog.open_or_create(root)
    with _progress_bar("meshes", progress) as update:
        report = import_meshes(catalog, folder, manifest, collection=name, workers=workers or None, progress=update)
    _print_summary("Mesh folder import", report.to_json(), catalog, as_json)
    _fail_if_nothing_imported(report.to_json())


@assets_app.command("procedural")
def procedural_cmd(
    count: int = typer.Option(2000, "--count", min=1, max=MAX_PROCEDURAL,
                              help=f"Number of procedural assets (default 2000, at most {MAX_PROCEDURAL:,})."),
    seed: int = typer.Option(0, "--seed", min=0, max=MAX_SEED,
                             help="Library seed, 0..2^32-1: the same seed gives byte-identical meshes."),
    library: Optional[Path] = typer.Option(None, "--library", help=LIBRARY_HELP),
    workers: int = typer.Option(0, "--workers", min=0, max=MAX_WORKERS, help="Worker processes (0 = one per CPU core)."),
    as_json: bool = typer.Option(False, "--json", help="Print the catalog stats as one JSON object."),
) -> None:
    """Build the built-in procedural library into the catalog (replaces earlier procedural assets)."""
    try:
        from ..assets.procedural import build_library
    except ImportError as e:
        raise AssetError(f"the procedural library is not available in this installation ({e})") from None

    root = resolve_library(library)
    kwargs = {}
    if "workers" in inspect.signature(build_library).parameters:
        kwargs["workers"] = workers or (os.cpu_count() or 1)
    t0 = time.perf_counter()
    catalog = build_library(root, count=count, seed=seed, **kwargs)
    seconds = time.perf_counter() - t0
    stats = catalog.stats().to_json()
    if as_json:
        sys.stdout.write(json.dumps({"catalog": str(root), "seconds": round(seconds, 2), "stats": stats}) + "\n")
        return

    Console().print(f"procedural library: {count} assets (seed {seed}) in {shown(root, 400, markup=True)}, "
                    f"{seconds:.1f} s; catalog now "
                    f"{stats['assets']} assets, {stats['classes']} classes, groups {stats['groups']}")


@assets_app.command("stats")
def stats_cmd(
    library: Optional[Path] = typer.Option(None, "--library", help=LIBRARY_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print exactly one JSON object (assets, classes, groups, "
                                                       "sources, skipped, per_class)."),
) -> None:
    """Counts per source, group and class, and the skipped assets with reasons."""
    from ..assets.catalog import Catalog

    root = resolve_library(library)
    catalog = Catalog.open(root)
    stats = catalog.stats().to_json()
    per_class = dict(sorted(Counter(r.class_name for r in catalog.records).items()))
    stats["per_class"] = per_class
    stats["library"] = str(root)
    if as_json:
        sys.stdout.write(json.dumps(stats) + "\n")
        return

    console = Console()
    t = Table(title=f"catalog {shown(root, 400, markup=True)}")
    t.add_column("what")
    t.add_column("count", justify="right")
    t.add_row("assets", str(stats["assets"]))
    t.add_row("classes", str(stats["classes"]))
    for g, n in stats["groups"].items():
        t.add_row(f"group {g}", str(n))
    for s, n in stats["sources"].items():
        t.add_row(f"source {shown(s, markup=True)}", str(n))
    t.add_row("skipped", str(len(stats["skipped"])))
    console.print(t)
    top = Counter(per_class).most_common(15)
    if top:
        console.print("most common classes: " + ", ".join(f"{shown(c, markup=True)} ({n})" for c, n in top))
    if stats["skipped"]:
        sk = Table(title="skipped")
        sk.add_column("path", overflow="fold")
        sk.add_column("reason", overflow="fold")
        for s in stats["skipped"]:
            sk.add_row(shown(s["path"], 400, markup=True), shown(s["reason"], markup=True))
        console.print(sk)


@assets_app.command("list")
def list_cmd(
    library: Optional[Path] = typer.Option(None, "--library", help=LIBRARY_HELP),
    group: Optional[str] = typer.Option(None, "--group", help="Only this group: floor, wall or obj."),
    class_name: Optional[str] = typer.Option(None, "--class", help="Only this class (exact, lower case)."),
    source: Optional[str] = typer.Option(None, "--source", help="Only this source (sh3d, meshes, procedural...)."),
    limit: int = typer.Option(0, "--limit", min=0, help="Show at most this many (0 = all)."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON list of records."),
) -> None:
    """List assets (id, class, groups, size in metres, supports)."""
    from ..assets.catalog import Catalog

    if group is not None and group not in GROUPS:
        raise ConfigError(f"--group {group!r}: expected one of {', '.join(GROUPS)}")
    catalog = Catalog.open(resolve_library(library))
    recs = catalog.group(group) if group else catalog.records
    if class_name:
        recs = tuple(r for r in recs if r.class_name == class_name.lower())
    if source:
        recs = tuple(r for r in recs if r.source == source)
    if limit:
        recs = recs[:limit]
    if as_json:
        sys.stdout.write(json.dumps([r.to_json() for r in recs]) + "\n")
        return

    t = Table(title=f"{len(recs)} assets")
    for col in ("id", "class", "groups", "size w x d x h (m)", "supports", "tris"):
        t.add_column(col, overflow="fold")
    for r in recs:
        t.add_row(shown(r.id, markup=True), shown(r.class_name, markup=True), ",".join(r.groups),
                  " x ".join(f"{s:.2f}" for s in r.size),
                  ",".join(f"{s.height:.2f}" for s in r.supports), str(r.triangles))
    Console().print(t)


def register(app: typer.Typer) -> None:
    app.add_typer(assets_app, name="assets")
