"""``assist3d probe``: how good is a training set for real scans? Train the segmenter on it for a fixed
budget, segment real scans zero-shot, score them with the ScanNet protocol.

Output folder (resumable; a finished seed is never redone, an unfinished one resumes from its
``last.pt``)::

    DIR/probe.json            the request (training sets, eval sets, budget, config); a re-run must match
    DIR/seed_K/last.pt        training state (safe checkpoint format, see checkpoint.py)
    DIR/seed_K/model.pt       the trained model (weights only)
    DIR/seed_K/pred/ID.npz    predictions per evaluation scene (masks, scores)
    DIR/seed_K/result.json    metrics of the seed (written last: the seed's completion marker)
    DIR/seed_K/pred_hybrid/   with ``hybrid=True``: predictions of hybrid inference, whose metrics are
                              added to result.json under ``hybrid``
    DIR/summary.json          runs, mean and std over seeds (the --json output; ``hybrid`` too)
    DIR/.train-pack-HOST-PID-*/  while seeds train: the training scenes as a scene pack (``pack.py``), read
                              once and trained from through memory maps; removed when the probe ends

The figures of ``runs``/``mean``/``std`` score the network's instances alone: the probe measures
training data, and the geometric proposals of hybrid inference do not depend on it. ``hybrid=True``
also scores what ``assist3d segment --method hybrid`` does (``hybrid.py``) with every seed's model, under
the key ``hybrid`` (its own ``runs``/``mean``/``std``); it is an evaluation option, not part of the
request, so it can be added to a finished folder without retraining. Each seed's hybrid figures
record the inference settings that made them (``inference``: the hybrid, geometric and superpoint
defaults of the code that ran); figures made with other settings are recomputed, never mixed. The
summary holds ``hybrid`` whenever every seed has figures for today's settings, with or without
``hybrid=True``.

Each seed's row names the precision its training steps computed in (``precision``: ``optim.precision:
auto`` is bfloat16 on CPUs that multiply it natively and float32 elsewhere, so the same command differs
between machines; ``bfloat16+float32`` for a seed resumed across both).

Metrics are pooled over all evaluation scenes like the benchmark; the bootstrap interval resamples
scenes with replacement (1,000 draws, 2.5th to 97.5th percentile).
"""

from __future__ import annotations

import json
import logging
import os
import subprocess
import sys
import time
from contextlib import ExitStack
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable, Iterator, Sequence

import numpy as np
import yaml

from ...data import open_dataset
from ...core import reading
from ...core.errors import ConfigError, DataError, FaultError, shown
from ...core.interrupts import set_parent_death_signal
from ...bench.evaluation.ap import METRIC_KEYS, SceneMatches, match_scene, summarize
from ...bench.evaluation.predictions import save_predictions
from ...core.fileio import write_json_atomic, write_text_atomic
from .checkpoint import load_segmenter, save_segmenter
from .config import BEFORE_ADDED, SegmenterConfig, legacy_config
from .data import Scene
from .hybrid import HYBRID_GEOMETRIC, HybridConfig
from .loader import mix_probabilities
from .pack import ScenePack, temporary_pack
from .predictor import STEPS, Predictor
from .superpoints import SuperpointConfig
from .train import Budget, precisions_of, train_segmenter

log = logging.getLogger(__name__)

RUN_KEYS: tuple[str, ...] = ("AP", "AP50", "AP25", "AR")
#: set by ``run_probe_jobs`` in each child's environment: the pid of the process that started it
PARENT_ENV = "ASSIST3D_PROBE_PARENT"
#: names, for the seed processes of ``--jobs``, the scene pack of the training scenes their parent wrote
PACK_ENV = "ASSIST3D_PROBE_PACK"
BOOTSTRAP_DRAWS = 1000


def hybrid_settings() -> dict:
    """The settings of hybrid inference as ``segment --method hybrid`` runs it today (stored with hybrid figures)."""
    return json.loads(json.dumps({"hybrid": asdict(HybridConfig()), "geometric": asdict(HYBRID_GEOMETRIC),
                                  "superpoint": asdict(SuperpointConfig())}))


#: The value a setting had before it was recorded, for figures stored without it (the plane refit of
#: hybrid inference came after the first hybrid figures were stored: those were made without it).
SETTINGS_BEFORE_RECORDED: dict[str, dict] = {"geometric": {"refine": 0}}


#: Options of hybrid inference that were measured, not adopted and taken out, with the value that meant
#: "off": figures stored with them off are today's, figures made with one on are not.
SETTINGS_RETIRED: dict[str, dict] = {"hybrid": {"stability_radii": [], "drop_structure": False, "snap_rank": False}}


def _without_retired(stored: dict) -> dict | None:
    """``stored`` without the :data:`SETTINGS_RETIRED` options it holds switched off; None if one was on."""
    out = dict(stored)
    for section, off in SETTINGS_RETIRED.items():
        part = out.get(section)
        if not isinstance(part, dict):
            continue
        if any(k in part and part[k] != v for k, v in off.items()):
            return None
        out[section] = {k: v for k, v in part.items() if k not in off}
    return out


def _current(stored: object) -> bool:
    """Whether hybrid figures made with the ``stored`` settings are today's. A setting missing from
    ``stored`` takes the value it had before it was recorded (``SETTINGS_BEFORE_RECORDED``), else
    today's default: options are added with defaults that keep the old behaviour, so figures written
    before an option existed stay valid, unless the option's default then changed. Retired options
    (``SETTINGS_RETIRED``) count only when they were on."""
    today = hybrid_settings()
    if not isinstance(stored, dict):
        return False
    stored = _without_retired(stored)
    if stored is None or set(stored) - set(today):
        return False
    return all(isinstance(stored.get(k, {}), dict)
               and {**v, **SETTINGS_BEFORE_RECORDED.get(k, {}), **stored.get(k, {})} == v for k, v in today.items())


@dataclass(frozen=True)
class ProbeRequest:
    train: tuple[str, ...]
    eval: tuple[str, ...]
    budget: Budget
    seeds: int
    config: SegmenterConfig
    max_train_scenes: int = 0
    #: one weight per training set (each of its scenes drawn that many times as often as a scene of
    #: weight 1, :func:`.loader.mix_probabilities`); () = every scene alike
    weights: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        if self.weights and len(self.weights) != len(self.train):
            raise ConfigError(f"{len(self.weights)} --weight values for {len(self.train)} --train sets: give one per set")

    @property
    def weighted(self) -> bool:
        return bool(self.weights) and len(set(self.weights)) > 1

    def as_dict(self) -> dict:
        out = {"train": list(self.train), "eval": list(self.eval), "budget": self.budget.as_dict(),
               "seeds": self.seeds, "max_train_scenes": self.max_train_scenes,
               "config": self.config.model_dump(mode="json")}
        if self.weighted:  # recorded only when it changes the draws, so folders from before resume
            out["weights"] = list(self.weights)
        return out


def _read_training_scenes(specs: Sequence[str], max_scenes: int,
                          progress: Callable[[int, int], None] | None) -> Iterator[tuple[int, Scene]]:
    """``(set index, scene)`` of every usable scene of every spec in order (the first ``max_scenes`` of
    each when > 0), read one at a time; a scene without points is skipped with a warning."""
    datasets = [open_dataset(s) for s in specs]
    jobs = [(k, ds, i) for k, ds in enumerate(datasets)
            for i in range(len(ds) if max_scenes <= 0 else min(max_scenes, len(ds)))]
    for n, (k, ds, i) in enumerate(jobs):
        sample = ds[i]
        if len(sample) == 0:
            log.warning("%s: scene %s has no points; skipped", ds.root, sample.scene_id)
        else:
            yield k, Scene.from_sample(sample)
        if progress is not None:
            progress(n + 1, len(jobs))


def load_training_scenes(specs: Sequence[str], max_scenes: int = 0,
                         progress: Callable[[int, int], None] | None = None) -> list[Scene]:
    """Every scene of every spec (the first ``max_scenes`` of each when > 0), kept compactly in memory."""
    scenes = [s for _, s in _read_training_scenes(specs, max_scenes, progress)]
    if not scenes:
        raise DataError(f"no usable training scenes in {', '.join(specs)}")
    return scenes


def pack_training_scenes(specs: Sequence[str], root: Path, max_scenes: int = 0,
                         progress: Callable[[int, int], None] | None = None) -> tuple[ScenePack, list[int]]:
    """:func:`load_training_scenes` into a :class:`.pack.ScenePack` in ``root`` instead of memory (the same
    scenes in the same order, never more than one in memory); also the number of scenes of each spec. The
    pack's ``info`` records the specs, ``max_scenes`` and those numbers (``train``, ``max_train_scenes``,
    ``sets``)."""
    sizes = [0] * len(specs)

    def counted() -> Iterator[Scene]:
        for k, scene in _read_training_scenes(specs, max_scenes, progress):
            sizes[k] += 1
            yield scene

    pack = ScenePack.write(root, counted(), info=lambda: {"train": list(specs), "max_train_scenes": max_scenes,
                                                          "sets": sizes})
    if len(pack) == 0:
        raise DataError(f"no usable training scenes in {', '.join(specs)}")
    return pack, sizes


def _mix_of(req: "ProbeRequest", pack: ScenePack, sizes: Sequence[int]) -> tuple[ScenePack, np.ndarray | None]:
    if not req.weighted:
        return pack, None
    for spec, n in zip(req.train, sizes):
        if n == 0:
            raise DataError(f"no usable training scenes in {spec}")
    return pack, mix_probabilities(sizes, req.weights)


def _training_mix(req: "ProbeRequest", root: Path,
                  progress: Callable[[int, int], None]) -> tuple[ScenePack, np.ndarray | None]:
    """The pooled training scenes, as a pack in ``root``, and, for a weighted request, their draw
    probabilities."""
    pack, sizes = pack_training_scenes(req.train, root, req.max_train_scenes, progress=progress)
    return _mix_of(req, pack, sizes)


def _shared_mix(req: "ProbeRequest") -> tuple[ScenePack, np.ndarray | None] | None:
    """The training scenes of a ``--jobs`` seed process: the pack its parent wrote (named by
    :data:`PACK_ENV`), when it holds this request's training sets; None otherwise."""
    path = os.environ.get(PACK_ENV)
    if not path or not os.environ.get(PARENT_ENV):  # only a seed process started by --jobs
        return None
    pack = ScenePack(path)
    info = pack.info
    if info.get("train") != list(req.train) or info.get("max_train_scenes") != req.max_train_scenes:
        log.warning("%s: holds other training sets than this probe's; reading them again", path)
        return None
    return _mix_of(req, pack, [int(n) for n in info.get("sets", [])])


def bootstrap(matches: Sequence[SceneMatches], seed: int = 0, draws: int = BOOTSTRAP_DRAWS) -> dict[str, list[float]]:
    """2.5 / 97.5 percentile interval of each metric over scenes resampled with replacement."""
    rng = np.random.default_rng(seed)
    n = len(matches)
    if n == 0:
        return {}
    vals = {k: [] for k in RUN_KEYS}
    for _ in range(draws):
        pick = rng.integers(n, size=n)
        s = summarize([matches[i] for i in pick]).summary
        for k in RUN_KEYS:
            vals[k].append(s[k])
    return {k: [float(np.nanpercentile(v, 2.5)), float(np.nanpercentile(v, 97.5))] for k, v in vals.items()}


def _num(x: float) -> float | None:
    return None if x is None or not np.isfinite(x) else round(float(x), 6)


def evaluate_model(model_path: Path, eval_specs: Sequence[str], pred_dir: Path, *, method: str = "learned",
                   on_scene: Callable[[int, int], None] | None = None) -> dict:
    """Segment every scene of ``eval_specs`` with the :class:`.predictor.Predictor` of ``method`` (a
    post-processing step of ``STEPS``: ``learned``, the network's instances; ``hybrid``,
    :func:`hybrid.segment_hybrid`; ``geometric``, the non-learned reference, which ignores ``model_path``; or
    any step registered with ``STEPS.add``), write predictions, return metrics with per-scene figures. An
    unknown ``method`` raises ``ConfigError`` naming the closest registered one."""
    predictor = Predictor(load_segmenter(model_path) if STEPS.get(method).needs_model else None, method)
    datasets = [open_dataset(s) for s in eval_specs]
    total = sum(len(d) for d in datasets)
    matches: list[SceneMatches] = []
    per_scene: dict[str, dict] = {}
    seconds = 0.0
    done = 0
    for ds in datasets:
        for sid in ds.scene_ids:
            sample = ds.load(sid)
            t0 = time.perf_counter()
            seg = predictor.segment(sample.coord, sample.color, name=sid, where=str(ds.root))
            seconds += time.perf_counter() - t0
            save_predictions(pred_dir / f"{sid}.npz", seg.masks, seg.scores)
            m = match_scene(sample.instance, seg.masks, seg.scores, valid=sample.valid, scene_id=sid)
            matches.append(m)
            s = summarize([m])
            per_scene[sid] = {**{k: _num(s[k]) for k in METRIC_KEYS}, "num_gt": s.num_gt, "num_pred": s.num_pred}
            done += 1
            if on_scene is not None:
                on_scene(done, total)
    overall = summarize(matches)
    return {**{k: _num(overall[k]) for k in METRIC_KEYS}, "num_gt": overall.num_gt, "num_pred": overall.num_pred,
            "scenes": len(matches), "predict_seconds": round(seconds, 2), "ci95": bootstrap(matches),
            "per_scene": per_scene}


def _open_out(out_dir: str | Path, req: ProbeRequest, first_seed: int) -> Path:
    """The probe folder for ``req``, created, with ``req`` recorded or checked against the one it holds."""
    if first_seed < 0:
        raise ConfigError(f"first seed {first_seed}: must be >= 0")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out}: exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    _check_request(out, req)
    return out


def _check_request(out: Path, req: ProbeRequest) -> None:
    path = out / "probe.json"
    mine = req.as_dict()
    if path.is_file():
        try:
            old = reading.read_json(path)
        except DataError as e:
            raise DataError(f"{e}; remove it or use another --out") from None
        stored = old.get("config") if isinstance(old, dict) else None
        missing = [(sec, key) for sec, key in BEFORE_ADDED
                   if isinstance(stored, dict) and isinstance(stored.get(sec), dict) and key not in stored[sec]]
        legacy = bool(missing)
        if isinstance(stored, dict):  # keys added since with their values of that time, retired ones dropped
            old = {**old, "config": legacy_config(stored, str(path))}
        old_cmp = {k: v for k, v in old.items() if k != "seeds"}
        new_cmp = {k: v for k, v in mine.items() if k != "seeds"}
        if old_cmp != new_cmp:
            diff = sorted(k for k in set(old_cmp) | set(new_cmp) if old_cmp.get(k) != new_cmp.get(k))
            then = ", ".join(f"{sec}.{key}: {BEFORE_ADDED[(sec, key)]}" for sec, key in missing)
            hint = (f"; it was started before {', '.join(f'{sec}.{key}' for sec, key in missing)} existed: "
                    f"a --config with {then} finishes it (configs/segmenter-pre-ema.yaml sets both)"
                    if legacy else "")
            raise ConfigError(f"{out}: holds a probe with other settings ({', '.join(diff)} differ); "
                              f"use another --out to start a new probe{hint}")
    write_json_atomic(path, mine)


def summarise_runs(runs: list[dict]) -> dict:
    """``runs`` with the ``mean`` and ``std`` (ddof 1; 0 for one run) of each metric over them."""
    out: dict = {"runs": runs, "mean": {}, "std": {}}
    for k in (*RUN_KEYS, "train_seconds", "steps"):
        vals = np.array([r[k] for r in runs if r.get(k) is not None], np.float64)
        out["mean"][k] = _num(vals.mean()) if len(vals) else None
        out["std"][k] = _num(vals.std(ddof=1)) if len(vals) > 1 else (0.0 if len(vals) == 1 else None)
    return out


def _run_row(seed: int, metrics: dict, meta: dict) -> dict:
    """One seed's figures as written to result.json (and to ``runs`` of the summary). ``precision``: what
    its training steps computed in (``optim.precision: auto`` follows the CPU, so the same command trains
    in bfloat16 on one machine and float32 on another; ``bfloat16+float32`` for a run resumed across
    both; None where the model does not say)."""
    used = precisions_of(meta)
    return {"seed": seed, **{k: metrics[k] for k in RUN_KEYS}, "AR50": metrics["AR50"], "AR25": metrics["AR25"],
            "train_seconds": round(float(meta.get("train_seconds", 0.0)), 1), "steps": int(meta.get("step", 0)),
            "precision": "+".join(used) or None,
            "ci95": metrics["ci95"], "per_scene": metrics["per_scene"], "predict_seconds": metrics["predict_seconds"]}


def _probe_seeds(req: ProbeRequest, out: Path, first_seed: int, hybrid: bool, emit: Callable[[str, dict], None],
                 *, device: str, loader_workers: int) -> list[dict]:
    """Each seed's row, trained and scored where it is not yet. The training scenes are read once, when a
    seed first needs them, into a scene pack in ``out`` (:mod:`.pack`) that is removed on return."""
    scenes: ScenePack | None = None
    probs: np.ndarray | None = None
    runs: list[dict] = []
    with ExitStack() as stack:
        for seed in range(first_seed, first_seed + req.seeds):
            sdir = out / f"seed_{seed}"
            result_path = sdir / "result.json"
            if result_path.is_file():
                run = reading.read_json(result_path)
                if not isinstance(run, dict):
                    raise DataError(f"{shown(result_path, 400)}: expected a JSON object; "
                                    "remove it to run the seed again")
                runs.append(_with_hybrid(run, sdir, req, seed, emit) if hybrid else run)
                emit("seed_done", {"seed": seed, "cached": True, **runs[-1]})
                continue
            model_path = sdir / "model.pt"
            if not model_path.is_file():
                if scenes is None:
                    emit("load_start", {})
                    scenes, probs = _shared_mix(req) or _training_mix(
                        req, stack.enter_context(temporary_pack(out)), lambda k, n: emit("load", {"done": k, "total": n}))
                emit("train_start", {"seed": seed})
                rec = train_segmenter(req.config, scenes, sdir, seed=seed, budget=req.budget,
                                      meta={"train": list(req.train)} | ({"weights": list(req.weights)} if req.weighted
                                                                         else {}),
                                      device=device, loader_workers=loader_workers, probs=probs,
                                      on_step=lambda row: emit("step", {"seed": seed, **row}))
                loaded = load_segmenter(rec.checkpoint)  # with optim.ema_decay: the averaged weights
                save_segmenter(model_path, loaded.model, req.config,
                               meta=loaded.meta | ({"weights": "ema"} if loaded.ema_state is not None else {}))
            meta = load_segmenter(model_path).meta
            emit("eval_start", {"seed": seed})
            metrics = evaluate_model(model_path, req.eval, sdir / "pred",
                                     on_scene=lambda k, n: emit("eval", {"seed": seed, "done": k, "total": n}))
            run = _run_row(seed, metrics, meta)
            write_json_atomic(result_path, run)  # the learned figures are kept even if hybrid scoring stops
            if hybrid:
                run = _with_hybrid(run, sdir, req, seed, emit)
            runs.append(run)
            emit("seed_done", {"seed": seed, "cached": False, **run})
    return runs


def run_probe(req: ProbeRequest, out_dir: str | Path, *, device: str = "cpu", loader_workers: int = 0,
              hybrid: bool = False, first_seed: int = 0,
              on_event: Callable[[str, dict], None] | None = None) -> dict:
    """Train and evaluate ``req.seeds`` seeds, ``first_seed`` onwards, into ``out_dir``; returns (and
    writes) the summary of those seeds. With ``hybrid``, every seed's model is also scored with hybrid
    inference (the summary's ``hybrid``). ``first_seed`` splits one probe over processes or machines:
    each writes its own ``seed_K`` folders, and a later call over the whole range reads them all."""
    out = _open_out(out_dir, req, first_seed)
    emit = on_event or (lambda kind, info: None)
    runs = _probe_seeds(req, out, first_seed, hybrid, emit, device=device, loader_workers=loader_workers)
    summary = summarise_runs([{k: v for k, v in r.items() if k != "hybrid"} for r in runs])
    if runs and all(isinstance(r.get("hybrid"), dict) and _current(r["hybrid"].get("inference")) for r in runs):
        summary["hybrid"] = summarise_runs([r["hybrid"] for r in runs])
    summary["request"] = req.as_dict()
    summary["seeds_run"] = [first_seed, first_seed + req.seeds - 1]  # the range this summary covers
    write_json_atomic(out / "summary.json", summary)
    return summary


def die_with_parent() -> None:
    """In a process started by ``run_probe_jobs``: be killed when that process dies (Linux), and stop now
    if it is already gone, so that no orphaned seed keeps training into its folder."""
    parent = os.environ.get(PARENT_ENV)
    if parent is None:
        return
    if str(os.getppid()) != parent:
        raise FaultError(f"the probe process {parent} that started this seed is gone; stopping")
    set_parent_death_signal()
    if str(os.getppid()) != parent:  # it died between the check and the call
        raise FaultError(f"the probe process {parent} that started this seed is gone; stopping")


def run_probe_jobs(req: ProbeRequest, out_dir: str | Path, *, jobs: int, device: str = "cpu",
                   loader_workers: int = 0, hybrid: bool = False, first_seed: int = 0, threads: int = 0,
                   on_event: Callable[[str, dict], None] | None = None) -> dict:
    """``run_probe`` with up to ``jobs`` seeds trained at once, each by its own ``assist3d probe --seeds 1
    --first-seed S`` process writing its ``seed_S`` folder (its log in ``DIR/jobs/seed_S.log``); then the
    summary over the seeds, read back. Meant for a GPU machine, where one process leaves the device
    partly idle (on an H200, four at once trained about 1.7 times the steps per second of one); on a
    CPU the processes share the cores. The training scenes are read once, by this process, into a scene
    pack (:mod:`.pack`) that every seed process reads."""
    if jobs < 1:
        raise ConfigError(f"--jobs {jobs}: must be at least 1")
    if req.budget.steps is None:
        raise ConfigError("--jobs needs a budget in --steps: processes that share the machine would each train "
                          "fewer steps in the same minutes than one alone")
    out = _open_out(out_dir, req, first_seed)
    emit = on_event or (lambda kind, info: None)
    seeds = range(first_seed, first_seed + req.seeds)
    todo = [s for s in seeds if not (out / f"seed_{s}" / "result.json").is_file()]
    logs = out / "jobs"
    logs.mkdir(exist_ok=True)
    cfg_path = logs / "config.yaml"
    write_text_atomic(cfg_path, yaml.safe_dump(req.config.model_dump(mode="json"), sort_keys=False))
    if threads == 0:  # "all cores" for each of the processes would oversubscribe them
        threads = max(1, (os.cpu_count() or 1) // jobs)
    base = [sys.executable, "-m", "assist3d", "probe", *[f"--train={t}" for t in req.train],
            *[f"--eval={e}" for e in req.eval], f"--steps={req.budget.steps}", f"--out={out}", f"--config={cfg_path}",
            f"--max-train-scenes={req.max_train_scenes}", f"--threads={threads}", f"--device={device}",
            f"--loader-workers={loader_workers}", "--json", *(["--hybrid"] if hybrid else []),
            *[f"--weight={w!r}" for w in req.weights]]
    child_env = {**os.environ, PARENT_ENV: str(os.getpid())}  # the child stops if this process dies
    with ExitStack() as stack:
        if any(not (out / f"seed_{s}" / "model.pt").is_file() for s in todo):  # some seed trains: share its scenes
            emit("load_start", {})
            root = stack.enter_context(temporary_pack(out))
            _training_mix(req, root, lambda k, n: emit("load", {"done": k, "total": n}))
            child_env[PACK_ENV] = str(root)
        _run_jobs(base, todo, jobs, logs, child_env, emit)
    return run_probe(req, out, device=device, loader_workers=loader_workers, hybrid=hybrid,
                     first_seed=first_seed, on_event=on_event)


def _run_jobs(base: list[str], todo: list[int], jobs: int, logs: Path, child_env: dict,
              emit: Callable[[str, dict], None]) -> None:
    """Run ``base --seeds=1 --first-seed=S`` for every seed of ``todo``, ``jobs`` at once; raise if any failed."""
    pending, running, failed = list(todo), {}, {}
    try:
        while pending or running:
            while pending and len(running) < jobs:
                seed = pending.pop(0)
                with open(logs / f"seed_{seed}.log", "w") as log:  # the child keeps its own descriptor
                    proc = subprocess.Popen([*base, "--seeds=1", f"--first-seed={seed}"], stdin=subprocess.DEVNULL,
                                            stdout=log, stderr=subprocess.STDOUT, env=child_env)
                running[seed] = proc
                emit("job_start", {"seed": seed, "running": len(running), "total": len(todo)})
            time.sleep(0.2)
            for seed, proc in list(running.items()):
                if proc.poll() is None:
                    continue
                del running[seed]
                if proc.returncode != 0:
                    failed[seed] = proc.returncode
                emit("job_done", {"seed": seed, "returncode": proc.returncode,
                                  "done": len(todo) - len(pending) - len(running), "total": len(todo)})
    finally:  # interrupted here: stop the running processes (a stopped seed resumes from its last.pt)
        for proc in running.values():
            proc.terminate()
        for proc in running.values():
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    if failed:
        names = ", ".join(f"seed {s} (exit {rc}, {logs / f'seed_{s}.log'})" for s, rc in sorted(failed.items()))
        msg = f"{len(failed)} of {len(todo)} probe processes failed: {names}; the finished seeds are kept"
        # exit status 2 is a refused input in every child: say so; anything else is a fault of the run
        raise (DataError if set(failed.values()) == {2} else FaultError)(msg)


def _with_hybrid(run: dict, sdir: Path, req: ProbeRequest, seed: int, emit: Callable[[str, dict], None]) -> dict:
    """``run`` (a seed's result.json) with its ``hybrid`` figures, computed from the seed's model.pt
    when missing or made with other inference settings, and then saved back into result.json; the
    other figures are unchanged."""
    if isinstance(run.get("hybrid"), dict) and _current(run["hybrid"].get("inference")):
        return run
    settings = hybrid_settings()
    model_path = sdir / "model.pt"
    if not model_path.is_file():
        raise DataError(f"{model_path}: not found, so seed {seed} cannot be scored with hybrid inference; "
                        f"remove {sdir} to train the seed again")
    emit("eval_start", {"seed": seed, "method": "hybrid"})
    metrics = evaluate_model(model_path, req.eval, sdir / "pred_hybrid", method="hybrid",
                             on_scene=lambda k, n: emit("eval", {"seed": seed, "done": k, "total": n,
                                                                 "method": "hybrid"}))
    row = _run_row(seed, metrics, {"train_seconds": run["train_seconds"], "step": run["steps"]}
                   | ({"precision": run["precision"]} if run.get("precision") else {}))
    run = {**run, "hybrid": {**row, "inference": settings}}
    write_json_atomic(sdir / "result.json", run)
    return run
