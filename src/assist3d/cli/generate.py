"""``assist3d generate | show | bench``: the dataset generator, a scene preview, a speed check."""

from __future__ import annotations

import json
import logging
import statistics
import sys
from pathlib import Path
from typing import List, Optional

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from ..core.bounds import MAX_SCENE_INDEX, MAX_SCENES, MAX_SEED, MAX_WORKERS, check_scene_indices
from ..core.errors import ConfigError
from ..config.presets import compose
from ..core.records import STAGES, stage_timings

log = logging.getLogger("assist3d.cli.generate")

MAX_BENCH_SCENES = 1000


def _stage_means(metas: list[dict]) -> dict[str, float]:
    out = {}
    for s in STAGES:
        vals = [stage_timings(m).get(s) for m in metas]
        out[s] = statistics.fmean(vals) if vals else 0.0
    return out


def _summary_table(run, console) -> None:
    entries = [e for e in run.manifest.entries if e.get("index") in set(run.requested)]
    t = Table(title=f"dataset {run.out}")
    t.add_column("")
    t.add_column("mean", justify="right")
    t.add_column("median", justify="right")
    t.add_column("min", justify="right")
    t.add_column("max", justify="right")

    def row(name: str, vals: list[float], fmt: str) -> None:
        if vals:
            t.add_row(name, fmt.format(statistics.fmean(vals)), fmt.format(statistics.median(vals)),
                      fmt.format(min(vals)), fmt.format(max(vals)))

    t.add_row("scenes", str(len(entries)), f"{len(run.generated)} new", f"{len(run.skipped)} kept", "")
    row("instances / scene", [float(e.get("instances", 0)) for e in entries], "{:.1f}")
    row("points / scene", [float(e.get("points", 0)) for e in entries], "{:,.0f}")
    row("dropped / scene", [float(e.get("dropped", 0)) for e in entries], "{:.1f}")
    fresh = run.generated
    for s in STAGES:
        row(f"seconds: {s}", [stage_timings(m).get(s) for m in fresh], "{:.3f}")
    row("seconds: total", [stage_timings(m).total for m in fresh], "{:.3f}")
    checks = [m["check"] for m in fresh if "check" in m]
    if checks:
        row("label agreement", [c["agreement"] for c in checks], "{:.5f}")
    console.print(t)


def _check_rays(rays: str | None) -> None:
    """``--rays``: None (the configuration's) or one of render.rays' values."""
    if rays not in (None, "full", "adaptive", "footprint"):
        raise typer.BadParameter(f"{rays!r}: expected full, adaptive or footprint", param_hint="--rays")


def register(app: typer.Typer) -> None:
    @app.command()
    def generate(
        out: Path = typer.Option(..., "--out", "-o", help="Output dataset folder (created; resumed if it exists)."),
        num_scenes: Optional[int] = typer.Option(None, "--num-scenes", "-n", min=1, max=MAX_SCENES,
                                                 help=f"Scenes 0..N-1 (at most {MAX_SCENES:,} per run)."),
        seed: Optional[int] = typer.Option(None, "--seed", min=0, max=MAX_SEED,
                                           help="Global seed, 0..2^32-1 (default: config, 0)."),
        workers: int = typer.Option(1, "--workers", "-w", min=1, max=MAX_WORKERS,
                                    help=f"Worker processes (at most {MAX_WORKERS})."),
        config: Optional[Path] = typer.Option(None, "--config", "-c", help="YAML config file."),
        assets: Optional[Path] = typer.Option(None, "--assets", help="Asset catalog folder (default: the default "
                                                                       "catalog if imported, else the built-in "
                                                                       "procedural library)."),
        preset: Optional[str] = typer.Option(None, "--preset", help="Generator preset (assist3d, randomrooms, "
                                                                      "holodeck-style, no-context, mesh-sampled, ...)."),
        save_mesh: bool = typer.Option(False, "--save-mesh", help="Also write each scene's scene.glb."),
        ply: bool = typer.Option(False, "--ply", help="Also write points.ply coloured by instance (kept scenes of "
                                                      "an earlier run get theirs too)."),
        llm_base_url: Optional[str] = typer.Option(None, "--llm-base-url", help="OpenAI-compatible endpoint."),
        llm_model: Optional[str] = typer.Option(None, "--llm-model", help="LLM model name."),
        only: Optional[List[int]] = typer.Option(None, "--only", help="Generate only scene K (repeatable)."),
        start: int = typer.Option(0, "--start", min=0, max=MAX_SCENE_INDEX, help="First scene index (with --count)."),
        count: Optional[int] = typer.Option(None, "--count", min=1, max=MAX_SCENES,
                                            help=f"Number of scenes from --start (at most {MAX_SCENES:,})."),
        verify: bool = typer.Option(False, "--verify", help="Re-cast rays and check every scene's labels."),
        as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
        backend: str = typer.Option("local", "--backend", help="local (worker processes on this machine) or ray "
                                                               "(one task per scene on a Ray cluster; needs the "
                                                               "\\[ray] extra and --out on storage every node sees)."),
        ray_address: Optional[str] = typer.Option(None, "--ray-address", help="Ray cluster HOST:PORT or "
                                                  "ray://HOST:PORT (default: Ray's discovery, else a new local "
                                                  "Ray)."),
        rays: Optional[str] = typer.Option(None, "--rays", help="render.rays: 'adaptive' (the ray budget, the "
                                           "default), 'footprint' (the ray budget, stopped where the kept pixels "
                                           "already sample every surface half a voxel apart) or 'full' (one ray per "
                                           "pixel: the reference, and the bytes of versions before the budget became "
                                           "the default)."),
    ) -> None:
        """Generate a dataset: one Pointcept-layout folder per scene plus manifest.json."""
        from ..pipeline import generate_dataset

        if backend not in ("local", "ray"):
            raise ConfigError(f"--backend must be local or ray, got {backend!r}")
        _check_rays(rays)
        overrides: dict = {}
        if rays is not None:
            overrides["render"] = {"rays": rays}
        if seed is not None:
            overrides["seed"] = seed
        if assets is not None:
            overrides.setdefault("assets", {})["library"] = str(assets)
        if save_mesh or ply:
            overrides["output"] = {**({"save_mesh": True} if save_mesh else {}), **({"ply": True} if ply else {})}
        if llm_base_url or llm_model:
            overrides["llm"] = {k: v for k, v in (("base_url", llm_base_url), ("model", llm_model)) if v}
        cfg = compose(config, preset, overrides)
        if only:
            indices = list(only)
        elif count is not None:
            indices = list(range(start, start + count))
        elif num_scenes is not None:
            indices = list(range(start, num_scenes))
        else:
            raise ConfigError("give --num-scenes N, --only K or --start S --count C")
        if not indices:
            raise ConfigError(f"no scenes selected (--start {start} is past --num-scenes {num_scenes})")
        check_scene_indices(indices, what="--only" if only else "--start/--count/--num-scenes")
        log.info("generating %d scenes into %s (preset %s, seed %d, %d worker%s)", len(indices), out, cfg.preset,
                 cfg.seed, workers, "s" if workers > 1 else "")
        err = Console(stderr=True)
        done_metas: list[dict] = []
        with Progress(TextColumn("[bold]scenes"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                      TimeRemainingColumn(), TextColumn("{task.fields[stages]}"), console=err,
                      disable=as_json) as bar:
            task = bar.add_task("scenes", total=len(indices), stages="")

            def on_start(total: int, already: int) -> None:
                bar.update(task, total=total)

            def on_scene(meta: dict, skipped: bool) -> None:
                if not skipped:
                    done_metas.append(meta)
                means = _stage_means(done_metas)
                stages = " ".join(f"{k} {v:.2f}" for k, v in means.items()) if done_metas else "resumed"
                bar.update(task, advance=1, stages=f"s/scene: {stages}")

            run = generate_dataset(cfg, out, indices, workers=workers, verify=verify, on_scene=on_scene,
                                   on_start=on_start, backend=backend, ray_address=ray_address)
        if as_json:
            sys.stdout.write(json.dumps({
                "out": str(out), "scenes": len(indices), "generated": len(run.generated), "skipped": len(run.skipped),
                "stages": _stage_means(run.generated), "failed_checks": run.failed_checks,
                "errors": run.errors, "exported_ply": run.exported,
                **({"cluster": run.cluster} if run.cluster else {})}) + "\n")
        else:
            _summary_table(run, Console())
            if run.exported:
                Console().print(f"--ply: wrote points.ply for {len(run.exported)} kept scene(s) generated without it")
            if run.cluster:
                c = run.cluster
                nodes = ", ".join(f"{n} {v['scenes']} ({v['scenes_per_minute']}/min)" for n, v in c["per_node"].items())
                Console().print(f"ray: {c['scenes']} scenes in {c['seconds']} s on {c['nodes']} node(s), "
                                f"{c['cpus']:g} CPUs: {c['scenes_per_minute']} scenes/min; per node: {nodes}")
        if run.failed_checks:
            log.error("label check failed for %d scenes: %s", len(run.failed_checks), ", ".join(run.failed_checks))
        if run.errors:
            log.error("%d scenes failed (re-run the same command to retry them): %s", len(run.errors),
                      ", ".join(run.errors))
        if run.failed_checks or run.errors:
            raise typer.Exit(1)

    @app.command()
    def show(
        path: Path = typer.Argument(..., help="A scene folder or a dataset folder (its first scene)."),
        out: Optional[Path] = typer.Option(None, "--out", "-o", help="PNG to write (default: "
                                           "<dataset>_<scene>_preview.png beside the dataset folder, never "
                                           "inside it)."),
        scene: Optional[str] = typer.Option(None, "--scene", help="Scene id inside a dataset folder."),
    ) -> None:
        """Picture a generated scene: top-down layout and the cloud coloured by instance."""
        from ..export.preview import beside_dataset, find_scene_dir, render_preview

        d = find_scene_dir(path, scene)
        png = render_preview(d, out or beside_dataset(path, d.name, "_preview.png"))
        typer.echo(str(png))

    @app.command()
    def bench(
        scenes: int = typer.Option(5, "--scenes", min=1, max=MAX_BENCH_SCENES,
                                   help=f"Scenes to generate (seeded, fixed; at most {MAX_BENCH_SCENES})."),
        assets: Optional[Path] = typer.Option(None, "--assets", help="Asset catalog folder."),
        seed: int = typer.Option(0, "--seed", min=0, max=MAX_SEED, help="Global seed of the benchmark scenes."),
        keep: Optional[Path] = typer.Option(None, "--keep", help="Write the scenes here instead of a temp folder."),
        as_json: bool = typer.Option(False, "--json", help="Print JSON only."),
        rays: Optional[str] = typer.Option(None, "--rays", help="render.rays: 'adaptive' (the ray budget, the default), "
                                                "'footprint' (sampled half a voxel apart) or 'full' (one ray per "
                                                "pixel, the reference)."),
    ) -> None:
        """Time the generator at paper settings (one worker): seconds per stage and peak memory."""
        from ..pipeline import run_benchmark

        _check_rays(rays)
        res = run_benchmark(scenes=scenes, assets=str(assets) if assets else None, seed=seed,
                            out=str(keep) if keep else None, rays=rays)
        if as_json:
            sys.stdout.write(json.dumps(res) + "\n")
            return

        t = Table(title=f"assist3d bench: {res['scenes']} scenes at paper settings, 1 worker, "
                        f"rays {res['settings']['rays']}")
        t.add_column("stage")
        t.add_column("median s", justify="right")
        for k, v in res["stages"].items():
            t.add_row(k, f"{v:.3f}")
        t.add_row("[bold]per scene (median)", f"[bold]{res['seconds_per_scene']['median']:.3f}")
        t.add_row("per scene (max)", f"{res['seconds_per_scene']['max']:.3f}")
        t.add_row("CPU s / scene before writing, all threads (median)", f"{res['cpu_seconds_per_scene']:.3f}")
        for k, v in res["cpu_stages"].items():
            t.add_row(f"  CPU s: {k}", f"{v:.3f}")
        t.add_row("peak memory, MB", f"{res['peak_memory_mb']:.0f}")
        t.add_row("points / scene (median)", f"{res['points_per_scene']:,.0f}")
        t.add_row("instances / scene (median)", f"{res['instances_per_scene']:.0f}")
        t.add_row("triangles / scene (median)", f"{res['triangles_per_scene']:,.0f}")
        m = res["machine"]
        t.caption = f"{m['cpu']}, {m['cores']} cores, {m['memory_gib']} GiB"
        Console().print(t)
