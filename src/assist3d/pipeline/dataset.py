"""The dataset loop around :class:`scene.SceneGenerator`: resumable (finished scenes are kept, a
folder lock keeps two runs apart), parallel over processes or a Ray cluster, deterministic per
scene; and the generation benchmark.
"""

from __future__ import annotations

import fcntl
import json
import logging
import multiprocessing as mp
import os
import re
import resource
import shutil
import socket
import statistics
import tempfile
import time
from concurrent.futures import FIRST_COMPLETED, wait
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable, Iterator

from . import ray_backend
from ..assets import open_catalog_for
from ..core.bounds import MAX_WORKERS, check_render_memory, check_scene_indices
from ..config import GenerateConfig, config_to_dict, dump_config, parse_config
from ..core.errors import AssistError, ConfigError, DataError, FaultError, describe_os_error, fault_advice, shown
from ..export import Manifest, read_scene_meta
from ..export.writer import export_scene_ply, remove_stale_temps
from ..core.interrupts import Interrupted, worker_pool
from ..core.machine import describe_machine, usable_cores
from ..core.records import STAGES, stage_timings
from ..core.rng import scene_seed
from ..planning.planners import make_planner
from .scene import SceneGenerator, SceneJob, check_plugins, scene_classes, scene_name

log = logging.getLogger(__name__)

_SCENE_RE = re.compile(r"^scene_(\d{6,})$")
THREAD_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


# ------------------------------------------------------------------------------------------
# worker processes
# ------------------------------------------------------------------------------------------

_WORKER: SceneGenerator | None = None


def _init_worker(cfg_json: dict, threads: int) -> None:
    global _WORKER
    _WORKER = SceneGenerator(parse_config(cfg_json), threads=threads)


def _run_job(job: SceneJob) -> dict:
    assert _WORKER is not None, "worker not initialised"
    return _WORKER.scene(job)


_WORKER_KEY: str | None = None


def _scene_in_ray_worker(cfg_json: dict, threads: int, job: SceneJob) -> tuple[dict, str]:
    """One scene in a Ray worker process: the local pool's worker, opened once per process and config."""
    global _WORKER_KEY
    key = json.dumps([cfg_json, threads], sort_keys=True)
    if _WORKER is None or key != _WORKER_KEY:
        for var in THREAD_ENV:
            os.environ.setdefault(var, "1")
        _init_worker(cfg_json, threads)
        _WORKER_KEY = key
    return _run_job(job), socket.gethostname()


# ------------------------------------------------------------------------------------------
# the dataset loop
# ------------------------------------------------------------------------------------------


@dataclass
class DatasetRun:
    """What :func:`generate_dataset` did."""

    out: Path
    requested: list[int]
    skipped: list[int]
    generated: list[dict]
    manifest: Manifest
    failed_checks: list[str]
    errors: list[str]  # scenes that raised an AssistError (not written; a re-run retries them)
    cluster: dict | None = None  # --backend ray: nodes, scenes per node, throughput (ray_backend.ClusterStats)
    exported: list[str] = field(default_factory=list)  # kept scenes given the points.ply they lacked (--ply)


LOCK_NAME = ".generate.lock"


@contextmanager
def _folder_lock(out: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``out`` (released by the OS even on SIGKILL); the lock file is
    removed when the run ends."""
    path = out / LOCK_NAME
    fd = _lock_file(path)
    try:
        yield
    finally:
        try:
            path.unlink(missing_ok=True)  # while still held: a run that opened it retries on a new file
        except OSError:  # a folder made read-only meanwhile: the unlocked file is harmless
            pass
        fcntl.flock(fd, fcntl.LOCK_UN)
        os.close(fd)


def _lock_file(path: Path) -> int:
    """Open and lock ``path``; retried if a finishing run removed the file we locked."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise DataError(f"{path.parent}: another `assist3d generate` is writing this folder") from None
        try:
            if os.path.samestat(os.fstat(fd), os.stat(path)):
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)


def _existing_scenes(out: Path) -> list[int]:
    if not out.is_dir():
        return []
    return sorted(int(m.group(1)) for p in out.iterdir() if p.is_dir() and (m := _SCENE_RE.match(p.name)))


def generate_dataset(cfg: GenerateConfig, out: str | Path, indices: Iterable[int], *, workers: int = 1,
                     verify: bool = False,
                     on_scene: Callable[[dict, bool], None] | None = None,
                     on_start: Callable[[int, int], None] | None = None,
                     backend: str = "local", ray_address: str | None = None) -> DatasetRun:
    """Generate scenes ``indices`` into ``out``; complete scenes already there are kept.

    ``backend="ray"`` runs every scene as a task on a Ray cluster (:mod:`assist3d.pipeline.ray_backend`;
    ``ray_address`` None = Ray's own discovery, else HOST:PORT); ``workers`` is then unused. The
    files are the same bytes as with ``workers=1``; ``out`` must be on storage every node sees.

    ``on_start(total, already_done)`` is called once, ``on_scene(meta, skipped)`` after every
    scene. The resolved config is saved as ``out/config.yaml``, the manifest as
    ``out/manifest.json`` (rewritten as scenes finish).

    On :class:`~assist3d.core.interrupts.Interrupted` (SIGINT / SIGTERM under the command line) the
    workers are stopped, half-written scene folders and temporary files removed, the folder lock
    released, and the exception re-raised with a detail saying how many scenes are complete.
    """
    indices = list(indices)
    try:
        return _generate_dataset(cfg, out, indices, workers=workers, verify=verify, on_scene=on_scene,
                                 on_start=on_start, backend=backend, ray_address=ray_address)
    except Interrupted as e:
        raise Interrupted(e.signum, _progress_line(Path(out), indices, cfg.seed)) from None
    except OSError as e:  # disk full, read-only, permissions: say what is complete and how to go on
        done, total = _complete(Path(out), indices, cfg.seed)
        raise FaultError(f"{describe_os_error(e, advice=False)}; {done} of {total} scenes complete in "
                         f"{shown(out, 400)}; {fault_advice(e)}, then re-run the same command to resume") from None


def _generate_dataset(cfg: GenerateConfig, out: str | Path, indices: Iterable[int], *, workers: int,
                      verify: bool, on_scene: Callable[[dict, bool], None] | None,
                      on_start: Callable[[int, int], None] | None, backend: str = "local",
                      ray_address: str | None = None) -> DatasetRun:
    if backend not in ("local", "ray"):
        raise ConfigError(f"--backend must be local or ray, got {backend!r}")
    if not 1 <= workers <= MAX_WORKERS:
        raise ConfigError(f"--workers must be 1..{MAX_WORKERS}, got {workers}")
    if backend == "ray":
        workers = 1  # the cluster decides; the driver opens the catalog once for the manifest
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: exists and is not a folder")
    indices = sorted(set(int(i) for i in indices))
    if any(i < 0 for i in indices):
        raise ConfigError("scene indices must be >= 0")
    check_scene_indices(indices)
    check_render_memory(cfg, workers=min(workers, len(indices)) or 1)  # before any work starts
    for var in THREAD_ENV:
        os.environ.setdefault(var, "1")
    cpus = usable_cores()
    threads = max(1, min(cfg.render.threads, cpus // workers)) if workers > 1 else cfg.render.threads
    check_plugins(cfg)  # an unregistered planner or ray caster is refused before anything is written
    if backend == "ray":
        ray_backend.connect(ray_address)  # before anything is written
    gen = SceneGenerator(cfg) if workers == 1 and backend == "local" else None  # in-process: open the catalog once
    if gen is not None:
        classes, assets_label = gen.classes, gen.assets_label
    else:
        cat = open_catalog_for(cfg.assets)
        classes = scene_classes(cat, cfg)
        assets_label = str(getattr(cat, "root", "") or cfg.assets.library or "procedural")
        make_planner(cfg)  # says once, here, which planner the workers use
        del cat
    cfg_dict = config_to_dict(cfg)
    manifest = Manifest(out, cfg_dict, cfg.seed, classes, assets_label)
    manifest.check_compatible()
    out.mkdir(parents=True, exist_ok=True)
    with _folder_lock(out):
        if remove_stale_temps(out):
            log.info("removed temporary files of an interrupted run in %s", out)
        dump_config(cfg, out / "config.yaml")

        todo: list[int] = []
        skipped: list[int] = []
        wanted = set(indices)
        for i in _existing_scenes(out):
            meta = read_scene_meta(out / scene_name(i), check_files=i in wanted)
            ok = meta is not None and meta.get("seed") == scene_seed(cfg.seed, i)
            if ok:
                manifest.add(meta)
                if i in wanted:
                    skipped.append(i)
        for i in indices:
            if i not in skipped:
                todo.append(i)
        if skipped:
            log.info("resume: %d of %d scenes already complete in %s", len(skipped), len(indices), out)
        exported = _complete_kept_scenes(cfg, out, skipped)
        manifest.write()
        if on_start:
            on_start(len(indices), len(skipped))
        for i in skipped:
            if on_scene:
                on_scene(next(e for e in manifest.entries if e.get("index") == i), True)

        generated: list[dict] = []
        failed: list[str] = []

        def done(meta: dict) -> None:
            generated.append(meta)
            manifest.add(meta)
            manifest.write()
            if verify and not meta.get("check", {}).get("ok", True):
                failed.append(meta["id"])
            if on_scene:
                on_scene(meta, False)

        errors: list[str] = []

        def fail(index: int, err: BaseException) -> None:
            if not isinstance(err, AssistError):
                raise err
            log.error("%s failed: %s", scene_name(index), err)  # the run goes on; a re-run retries it
            errors.append(scene_name(index))

        jobs = [SceneJob(i, str(out), verify) for i in todo]
        cluster = None
        try:
            if backend == "ray":
                if jobs:
                    stats = ray_backend.run_scenes(_scene_in_ray_worker, (cfg_dict, 1), jobs, done, fail, out=out,
                                                  address=ray_address)
                    cluster = stats.as_dict()
            elif gen is not None:
                _run_in_process(gen, jobs, done, fail)
            elif jobs:
                _run_in_pool(jobs, workers, cfg_dict, threads, done, fail)
        except (Interrupted, OSError, KeyboardInterrupt):  # half-written scenes go, complete ones stay
            _discard_unfinished(out, todo)
            raise
        finally:
            if backend == "ray":
                ray_backend.disconnect()
        return DatasetRun(out, indices, skipped, generated, manifest, failed, errors, cluster, exported)


def _complete_kept_scenes(cfg: GenerateConfig, out: Path, kept: list[int]) -> list[str]:
    """The extra files a resumed run asks for, for the scenes it keeps: ``output.ply`` writes the
    missing ``points.ply`` from the arrays (the bytes a fresh run writes); ``output.save_mesh`` cannot
    (the mesh is assembled while a scene is generated) and says so. Returns the scenes given a PLY."""
    exported: list[str] = []
    if cfg.output.ply:
        exported = [scene_name(i) for i in kept if export_scene_ply(out / scene_name(i))]
        if exported:
            log.info("--ply: wrote points.ply for %d kept scene%s generated without it", len(exported),
                     "s" if len(exported) > 1 else "")
    if cfg.output.save_mesh:
        lacking = [scene_name(i) for i in kept if not (out / scene_name(i) / "scene.glb").is_file()]
        if lacking:
            log.warning("--save-mesh: %d kept scene%s (%s%s) have no scene.glb and get none: the mesh is only "
                        "written while a scene is generated; delete those scene folders, or use another --out, "
                        "to generate them with it", len(lacking), "s" if len(lacking) > 1 else "",
                        ", ".join(lacking[:3]), ", ..." if len(lacking) > 3 else "")
    return exported


def _run_in_process(gen: SceneGenerator, jobs: list[SceneJob], done: Callable[[dict], None],
                    fail: Callable[[int, BaseException], None]) -> None:
    for job in jobs:
        try:
            meta = gen.scene(job)
        except AssistError as e:
            fail(job.index, e)
            continue
        done(meta)


def _run_in_pool(jobs: list[SceneJob], workers: int, cfg_dict: dict, threads: int, done: Callable[[dict], None],
                 fail: Callable[[int, BaseException], None]) -> None:
    """Scenes in worker processes (stopped at once if this process is interrupted)."""
    ctx = mp.get_context("forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn")
    with worker_pool(min(workers, len(jobs)), mp_context=ctx, initializer=_init_worker,
                     initargs=(cfg_dict, threads)) as pool:
        futures = {pool.submit(_run_job, j): j.index for j in jobs}
        pending = set(futures)
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for f in finished:
                if f.exception() is not None:
                    fail(futures[f], f.exception())
                else:
                    done(f.result())


def _discard_unfinished(out: Path, indices: Iterable[int]) -> None:
    """After an interrupt or a fault: remove the half-written folders of scenes ``indices`` (no
    completion marker) and temporary files in ``out``; complete scenes stay."""
    try:
        for i in indices:
            d = out / scene_name(i)
            if d.is_dir() and read_scene_meta(d, check_files=False) is None:
                shutil.rmtree(d, ignore_errors=True)
        remove_stale_temps(out)
    except OSError:  # a read-only folder: what is left is incomplete and redone on resume
        pass


def _complete(out: Path, indices: list[int], seed: int) -> tuple[int, int]:
    """(complete scenes of ``indices`` in ``out``, read from disk; how many were asked for)."""
    wanted = {int(i) for i in indices}
    complete = 0
    for i in wanted:
        meta = read_scene_meta(out / scene_name(i), check_files=False)
        complete += meta is not None and meta.get("seed") == scene_seed(seed, i)
    return complete, len(wanted)


def _progress_line(out: Path, indices: list[int], seed: int) -> str:
    """``"3 of 20 scenes complete in OUT; re-run the same command to resume"``, read from disk."""
    complete, total = _complete(out, indices, seed)
    return f"{complete} of {total} scenes complete in {shown(out, 400)}; re-run the same command to resume"


def run_benchmark(*, scenes: int = 5, assets: str | None = None, seed: int = 0, out: str | None = None,
                  cfg: GenerateConfig | None = None, rays: str | None = None) -> dict:
    """Generate ``scenes`` scenes at paper settings with one worker; per-stage medians and peak
    memory (max resident set size of this process, which includes the opened catalog).

    Returns ``{"scenes", "seconds_per_scene": {"median", "max"}, "stages": {stage: median s},
    "peak_memory_mb", ..., "machine"}`` (the machine: :func:`assist3d.core.machine.describe_machine`).
    Opening (or first building) the catalog is timed separately.
    ``cfg`` replaces the paper settings (tests use a tiny one); ``rays`` sets ``render.rays`` (the
    reference render ``full`` or the ray budget ``adaptive``; default: the configuration's).
    """
    if cfg is None:
        cfg = parse_config({"seed": seed, "assets": {"library": assets}})
    if rays is not None:
        render = type(cfg.render).model_validate(cfg.render.model_dump() | {"rays": rays})
        cfg = cfg.model_copy(update={"render": render})
    check_render_memory(cfg)
    t0 = time.perf_counter()
    gen = SceneGenerator(cfg)
    catalog_s = time.perf_counter() - t0
    with tempfile.TemporaryDirectory(prefix="assist3d-bench-") as tmp:
        root = Path(out) if out else Path(tmp)
        metas = [gen.scene(SceneJob(i, str(root))) for i in range(scenes)]
    totals = [stage_timings(m).total for m in metas]
    peak_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {
        "scenes": scenes,
        "seconds_per_scene": {"median": round(statistics.median(totals), 4), "max": round(max(totals), 4)},
        "stages": {s: round(statistics.median(stage_timings(m).get(s) for m in metas), 4) for s in STAGES},
        "peak_memory_mb": round(peak_kb / 1024.0, 1),
        "cpu_seconds_per_scene": round(statistics.median(sum(m["cpu_seconds"].values()) for m in metas), 4),
        "cpu_stages": {k: round(statistics.median(m["cpu_seconds"][k] for m in metas), 4)
                       for k in metas[0]["cpu_seconds"]},
        "points_per_scene": statistics.median(m["points"] for m in metas),
        "instances_per_scene": statistics.median(m["instances"] for m in metas),
        "triangles_per_scene": statistics.median(m["triangles"] for m in metas),
        "catalog_seconds": round(catalog_s, 3),
        "settings": {"views": metas[0]["render"]["views"], "width": cfg.render.width, "height": cfg.render.height,
                     "voxel_size": cfg.render.voxel_size, "backend": cfg.render.backend,
                     "rays": cfg.render.rays},
        "machine": describe_machine(),
    }
