#!/usr/bin/env python
"""Bad inputs and faults over every ``assist3d`` command, each run in a subprocess and classified.

Usage::

    .venv/bin/python scripts/fuzz_cli.py [--json results.json] [--only SUBSTRING] [--keep]

Every case runs the command line (``python -m assist3d ...``) in its own process group with a
time limit, inside a temporary folder holding tiny fixtures built first (a 2-scene dataset from
the built-in procedural library, a layout, an (N, 8) scan, predictions, checkpoints, meshes).
Each outcome is classified:

``clear``      the expected answer: a non-zero exit with a short message naming the input (or,
               where the case says so, success / a warning naming it), no Python traceback
``traceback``  a Python traceback reached the user
``silent``     exit 0 on bad input with no warning
``unclear``    an error that does not name the input, or a failure where success was expected
``hang``       the time limit ran out, or a process of the run outlived it
``loss``       complete data written before (hashed) changed or disappeared
``escape``     code ran from data (a marker file appeared), a file outside its folder was used,
               or a raw control character (ESC, BEL, CSI) reached the output

It prints a markdown table (case, command, expected, outcome, class) and a summary line, writes
the results as JSON with ``--json``, and exits 1 if any outcome is not ``clear``.

Faults that need privileges: read-only folders use a folder with mode 0555 and the command run
without the CAP_DAC_OVERRIDE / CAP_DAC_READ_SEARCH capabilities (``setpriv``), because root
ignores permissions; read-only file systems and disk full use small tmpfs mounts
(``mount -t tmpfs``); ``/dev/full`` is a character device node made with ``mknod`` inside the
temporary folder (never the real ``/dev/full``: an atomic writer running as root would rename its
temporary file over it). Cases whose fault the machine cannot make are skipped with the reason.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import pickle
import platform
import re
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CLASSES = ("clear", "traceback", "silent", "unclear", "hang", "loss", "escape")
RAW_CONTROLS = ("\x1b", "\x07", "\x9b")
ESC_NAME = "\x1b]0;pwned\x07\x1b[2J"  # retitles the terminal and clears the screen if shown raw

TINY_GEN = {
    "seed": 11,
    "assets": {"procedural_count": 60},
    "selection": {"floor_count": 6, "wall_count": 2, "on_top_count": 1},
    "room": {"area_min": 10.0, "area_max": 16.0},
    "layout": {"group_budget_s": 120.0},
    "render": {"width": 80, "height": 60, "fx": 72.2, "fy": 72.2, "vantage_points": 2, "views_per_point": 6},
}
TINY_TRAIN = {
    "threads": 1,
    "model": {"stem_channels": 8, "stem_kernel": 3, "enc_channels": [8, 16, 16, 24], "enc_blocks": [1, 1, 1, 1],
              "dec_channels": [24, 16, 16, 16], "dec_blocks": [1, 1, 1, 1], "hidden": 32, "heads": 4, "ffn": 64,
              "num_passes": 1, "num_queries": 12, "num_queries_eval": 12},
    "data": {"voxel_size": 0.1},
    "augment": {"enabled": False},
    "optim": {"lr": 0.003, "batch_size": 2, "epochs": 1, "pct_start": 0.5},
    "predict": {"top_k": 12},
}
TINY_NET = {"net": {"voxel_size": 0.1, "stem_channels": 8, "enc_channels": [8, 16, 16, 24],
                    "dec_channels": [24, 16, 16, 16]},
            "augment": {"crop_m": 0.0}, "optim": {"batch_size": 2, "lr": 0.01}}


# ------------------------------------------------------------------------------------------------
# running one command


@dataclass
class Result:
    rc: int | None
    out: str
    err: str
    seconds: float
    timed_out: bool

    @property
    def text(self) -> str:
        return self.out + self.err


def run_cli(argv: list[str], env: dict[str, str], cwd: Path, timeout: float, prefix: tuple[str, ...] = ()) -> Result:
    """``python -m assist3d ARGV`` in a new process group; the whole group is killed on time-out."""
    cmd = [*prefix, sys.executable, "-m", "assist3d", *argv]
    t0 = time.monotonic()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, cwd=cwd,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
        timed_out = False
    except subprocess.TimeoutExpired:
        kill_group(proc.pid)
        out, err = proc.communicate()
        timed_out = True
    return Result(proc.returncode, out.decode("utf-8", "replace"), err.decode("utf-8", "replace"),
                  time.monotonic() - t0, timed_out)


def kill_group(pgid: int) -> None:
    try:
        os.killpg(pgid, signal.SIGKILL)
    except ProcessLookupError:
        pass


# ------------------------------------------------------------------------------------------------
# processes below a pid (for "no process outlives the run")


from assist3d.testing import descendants, wait_until_gone  # noqa: E402


def survivors(procs: dict[int, str], wait_s: float = 5.0) -> list[int]:
    return wait_until_gone(procs, wait_s)


# ------------------------------------------------------------------------------------------------
# data hashes (for "no complete data is lost")


def scene_digest(root: Path) -> dict[str, str]:
    """One hash per complete scene over its arrays and its layout (wall-clock timings left out)."""
    out: dict[str, str] = {}
    for d in sorted(root.glob("scene_*")):
        if not (d / "meta.json").is_file():
            continue
        h = hashlib.sha256()
        try:
            for name in ("coord.npy", "color.npy", "normal.npy", "instance.npy", "segment.npy"):
                h.update((d / name).read_bytes())
            lay = json.loads((d / "layout.json").read_text())
        except (OSError, ValueError):
            out[d.name] = "unreadable"
            continue
        lay.pop("seconds", None)
        lay.get("stats", {}).pop("timing", None)
        h.update(json.dumps(lay, sort_keys=True).encode())
        out[d.name] = h.hexdigest()
    return out


def lost(before: dict[str, str], after: dict[str, str]) -> list[str]:
    return [k for k, v in before.items() if after.get(k) != v]


# ------------------------------------------------------------------------------------------------
# cases


@dataclass
class Case:
    name: str
    argv: list[str]
    expect: str  # what a careful user should see
    names: tuple[str, ...] = ()  # the message must contain one of these (whitespace ignored)
    want: str = "error"  # error | ok | warn (success with a warning naming the input, or a clear error)
    timeout: float = 60.0
    prefix: tuple[str, ...] = ()
    prepare: Callable[[], None] | None = None
    check: Callable[[Result], tuple[str, str] | None] | None = None  # (class, note) overrides
    runner: Callable[["Case"], Result] | None = None
    skip: str | None = None
    owner: str = ""  # who fixes a non-clear outcome, if not this script's author (noted in the table)


@dataclass
class Outcome:
    case: Case
    cls: str
    note: str
    rc: int | None = None
    seconds: float = 0.0
    message: str = ""


WARN_RE = re.compile(r"\b(WARNING|ERROR|warning)\b")
BOX = "─│╭╮╰╯┃━┏┓┗┛╇┡┩└┘┌┐├┤┬┴┼┳┻╋"


def _squash(text: str) -> str:
    return "".join(text.split()).replace("│", "")


def _lines(text: str) -> list[str]:
    """Non-empty lines without table borders and progress bars."""
    out = []
    for ln in text.splitlines():
        ln = ln.strip(" " + BOX)
        drawn = sum(ch in BOX for ch in ln)
        if ln and drawn <= len(ln) // 3:
            out.append(" ".join(ln.replace("│", " ").split()))
    return out


def message_of(res: Result) -> str:
    """The line a user reads: the last error-looking lines of stderr, else the last line of
    stdout (a summary), else of stderr."""
    keys = ("Error", "error", "ERROR", "assist3d:", "Invalid", "invalid", "WARNING", "No such", "Missing", "Got")
    err, out = _lines(res.err), _lines(res.out)
    picked = [ln for ln in err if any(k in ln for k in keys)]
    if picked:
        return " / ".join(picked[-2:])
    lines = out or err
    return lines[-1] if lines else ""


def names_input(case: Case, res: Result) -> bool:
    if not case.names:
        return True
    text = _squash(res.text)
    return any(_squash(n) in text for n in case.names)


def classify(case: Case, res: Result) -> tuple[str, str]:
    if res.timed_out:
        return "hang", f"no answer after {case.timeout:.0f} s"
    if case.check is not None and (verdict := case.check(res)) is not None:
        return verdict
    raw = [repr(c) for c in RAW_CONTROLS if c in res.text]
    if raw:
        return "escape", f"raw control character(s) {', '.join(raw)} in the output"
    if "Traceback (most recent call last)" in res.text:
        return "traceback", "a Python traceback"
    warned = bool(WARN_RE.search(res.err)) and names_input(case, res)
    if case.want == "ok":
        return ("clear", "") if res.rc == 0 else ("unclear", f"expected success, exit {res.rc}")
    if res.rc == 0:
        if warned:
            return "clear", "accepted with a warning naming it"
        return "silent", "exit 0" if case.want == "error" else "exit 0 without a warning"
    if not names_input(case, res):
        return "unclear", f"the message names none of {list(case.names)}"
    if "errors.pydantic.dev" in res.text or "validation error for" in res.text:
        return "unclear", "a raw pydantic validation dump instead of a message"
    return "clear", ""


def run_case(case: Case, env: dict[str, str], cwd: Path) -> Outcome:
    if case.skip:
        return Outcome(case, "skipped", case.skip)
    if case.prepare is not None:
        case.prepare()
    res = case.runner(case) if case.runner else run_cli(case.argv, env, cwd, case.timeout, case.prefix)
    cls, note = classify(case, res)
    return Outcome(case, cls, note, res.rc, res.seconds, message_of(res))


# ------------------------------------------------------------------------------------------------
# fixtures


@dataclass
class Fixtures:
    root: Path
    env: dict[str, str]
    cwd: Path
    tiny: Path  # generator config
    base: Path  # a complete 2-scene dataset
    base_digest: dict[str, str]
    ref4: dict[str, str]  # digests of the 4-scene dataset of TINY_GEN
    layout: Path
    scan: Path  # (N, 8) array scan
    gt: Path  # array folder holding scan
    preds: Path  # predictions for gt
    train_cfg: Path
    ckpt: Path  # a valid engine checkpoint
    seg_ckpt: Path  # a valid segmenter checkpoint
    seg_cfg: Path
    meshes: Path
    manifest: Path
    tmpfs_ok: str | None  # None if tmpfs mounts work, else why not
    setpriv_ok: str | None
    devfull: Path | None
    mounts: list[Path] = field(default_factory=list)

    @property
    def proc_lib(self) -> Path:
        """The built-in procedural catalog the tiny config builds (in the fuzz cache)."""
        return self.root / "cache" / f"procedural-{TINY_GEN['assets']['procedural_count']}-0"

    def path(self, *parts: str) -> Path:
        p = self.root.joinpath("cases", *parts)
        p.parent.mkdir(parents=True, exist_ok=True)
        return p

    def write(self, rel: str, data: bytes | str) -> Path:
        p = self.path(rel)
        p.write_bytes(data.encode() if isinstance(data, str) else data)
        return p

    def copy_base(self, rel: str) -> Path:
        dst = self.path(rel)
        shutil.copytree(self.base, dst)
        return dst

    def mount_tmpfs(self, rel: str, size: str, *, read_only: bool = False) -> Path:
        p = self.path(rel)
        p.mkdir(parents=True, exist_ok=True)
        opts = f"size={size}" + (",ro" if read_only else "")
        subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(p)], check=True, capture_output=True)
        self.mounts.append(p)
        return p

    def full_tmpfs(self, rel: str, subdirs: tuple[str, ...] = ()) -> Path:
        """A 256 KiB tmpfs filled to the last byte, with empty folders ``subdirs`` made first."""
        p = self.mount_tmpfs(rel, "256k")
        for s in subdirs:
            (p / s).mkdir(parents=True)
        try:
            with open(p / "filler", "wb") as f:
                while True:
                    f.write(b"\0" * 4096)
                    f.flush()
        except OSError:
            pass
        return p


def _try(cmd: list[str]) -> str | None:
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as e:
        return f"{cmd[0]}: {e}"
    return None if r.returncode == 0 else f"{' '.join(cmd[:3])}: {(r.stderr or r.stdout).strip()[:120]}"


def _probe_privileges(root: Path) -> tuple[str | None, str | None, Path | None]:
    """(tmpfs problem or None, setpriv problem or None, /dev/full-like node or None)."""
    probe = root / "mnt-probe"
    probe.mkdir()
    tmpfs = _try(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(probe)])
    if tmpfs is None:
        _try(["umount", str(probe)])
    if os.geteuid() != 0:
        setpriv = None  # permissions apply anyway; no capability to drop
    else:
        setpriv = _try(["setpriv", "--bounding-set=-dac_override,-dac_read_search", "true"])
    devfull: Path | None = root / "full"
    try:
        os.mknod(devfull, 0o666 | 0o020000, os.makedev(1, 7))
    except (OSError, AttributeError):
        devfull = None
    return tmpfs, setpriv, devfull


def _no_dac() -> tuple[str, ...]:
    return ("setpriv", "--bounding-set=-dac_override,-dac_read_search") if os.geteuid() == 0 else ()


def build_fixtures(root: Path) -> Fixtures:
    import yaml

    env = {k: v for k, v in os.environ.items() if k not in ("ASSIST3D_ASSETS", "OPENAI_API_KEY")}
    env.update({"ASSIST3D_CACHE": str(root / "cache"), "COLUMNS": "200", "PYTHONPATH": str(ROOT / "src"),
                "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"})
    os.environ.update({k: env[k] for k in ("ASSIST3D_CACHE",)})
    os.environ.pop("ASSIST3D_ASSETS", None)
    cwd = root / "cwd"
    cwd.mkdir()
    tiny = root / "tiny.yaml"
    tiny.write_text(yaml.safe_dump(TINY_GEN))

    from assist3d.config import parse_config
    from assist3d.pipeline import generate_dataset

    base = root / "base"
    generate_dataset(parse_config(TINY_GEN), base, range(2))
    ref4_dir = root / "ref4"
    generate_dataset(parse_config(TINY_GEN), ref4_dir, range(4))
    ref4 = scene_digest(ref4_dir)
    shutil.rmtree(ref4_dir)

    layout = base / "scene_000000" / "layout.json"
    d = base / "scene_000000"
    inst = np.load(d / "instance.npy")
    scan_arr = np.concatenate([np.load(d / "coord.npy"), np.load(d / "color.npy").astype(np.float32),
                               np.where(inst >= 0, 5, 1)[:, None].astype(np.float32),
                               inst[:, None].astype(np.float32)], axis=1).astype(np.float32)
    gt = root / "gt"
    gt.mkdir()
    scan = gt / "scan.npy"
    np.save(scan, scan_arr)
    preds = root / "preds"
    from assist3d.bench.evaluation.predictions import save_predictions

    ids = np.unique(inst[inst >= 0])
    save_predictions(preds / "scan.npz", np.stack([inst == i for i in ids]), np.linspace(1, 0.5, len(ids)).astype(np.float32))

    train_cfg = root / "train.yaml"
    train_cfg.write_text(yaml.safe_dump(TINY_TRAIN))
    seg_cfg = root / "seg.yaml"
    seg_cfg.write_text(yaml.safe_dump(TINY_NET))
    ckpt, seg_ckpt = _checkpoints(root)

    meshes = root / "meshes"
    meshes.mkdir()
    (meshes / "box.obj").write_text(_box_obj())
    manifest = root / "manifest.csv"
    manifest.write_text("path,class,groups,size\nbox.obj,box,floor,\"1,1,1\"\n")

    tmpfs, setpriv, devfull = _probe_privileges(root)
    return Fixtures(root, env, cwd, tiny, base, scene_digest(base), ref4, layout, scan, gt, preds, train_cfg,
                    ckpt, seg_ckpt, seg_cfg, meshes, manifest, tmpfs, setpriv, devfull)


def _checkpoints(root: Path) -> tuple[Path, Path]:
    import torch

    from assist3d.learn.engine.config import parse_train_config
    from assist3d.learn.engine.toy import make_toy_scene
    from assist3d.learn.engine.train import MemorySource, train
    from assist3d.learn.segmenter.checkpoint import save_segmenter
    from assist3d.learn.segmenter.config import parse_segmenter_config
    from assist3d.learn.segmenter.model import Segmenter

    torch.set_num_threads(1)
    scenes = [make_toy_scene(f"s{i}", rng=np.random.default_rng(i), num_objects=3, room_m=3.0, density_per_m2=150)
              for i in range(2)]
    train(parse_train_config(TINY_TRAIN), root / "run", source=MemorySource(scenes))
    cfg = parse_segmenter_config(TINY_NET)
    torch.manual_seed(0)
    seg = save_segmenter(root / "seg.pt", Segmenter(cfg.net), cfg)
    return root / "run" / "last.pt", Path(seg)


def _box_obj() -> str:
    v = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    f = [(1, 3, 4, 2), (5, 6, 8, 7), (1, 2, 6, 5), (3, 7, 8, 4), (1, 5, 7, 3), (2, 4, 8, 6)]
    return "".join(f"v {x} {y} {z}\n" for x, y, z in v) + "".join(f"f {a} {b} {c} {d}\n" for a, b, c, d in f)


class Evil:
    """Unpickling this runs ``touch MARKER``."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return os.system, (f"touch {self.marker}",)


def evil_checkpoint(path: Path, marker: Path, *, torch_format: bool) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if torch_format:
        import torch

        torch.save({"model": Evil(marker), "config": {}}, path)
    else:
        path.write_bytes(pickle.dumps({"model": Evil(marker)}))
    return path


def marker_check(marker: Path) -> Callable[[Result], tuple[str, str] | None]:
    def check(res: Result) -> tuple[str, str] | None:
        if marker.exists():
            return "escape", f"code from the file ran: {marker.name} was created"
        return None

    return check


def unchanged_check(root: Path, before: dict[str, str]) -> Callable[[Result], tuple[str, str] | None]:
    def check(res: Result) -> tuple[str, str] | None:
        gone = lost(before, scene_digest(root))
        return ("loss", f"complete scenes changed or lost: {gone}") if gone else None

    return check


# ------------------------------------------------------------------------------------------------
# the cases, command by command


def yaml_case(fx: Fixtures, name: str, text: str, expect: str, names: tuple[str, ...], cmd: str = "generate",
              want: str = "error") -> Case:
    cfg = fx.write(f"{name}.yaml", text)
    out = fx.path(name + "-out")
    argv = {"generate": ["generate", "--out", str(out), "--num-scenes", "1", "--config", str(cfg)],
            "layout": ["layout", "--out", str(out), "--no-glb", "--config", str(cfg)]}[cmd]
    return Case(name, argv, expect, names, want=want, timeout=40)


def generate_cases(fx: Fixtures) -> list[Case]:
    g = ["generate", "--config", str(fx.tiny)]
    t = fx.tiny.read_text()
    afile = fx.write("gen-file", "x")
    cases = [
        Case("generate-out-is-file", [*g, "--out", str(afile), "-n", "1"], "refused: not a folder", ("gen-file",)),
        Case("generate-out-under-file", [*g, "--out", str(afile / "sub"), "-n", "1"], "refused: a parent is a file",
             ("gen-file",)),
        Case("generate-num-scenes-1e12", [*g, "--out", str(fx.path("g-big")), "-n", str(10**12)],
             "refused before work: bound on scenes", ("--num-scenes", "scenes"), timeout=30),
        Case("generate-count-1e12", [*g, "--out", str(fx.path("g-cnt")), "--count", str(10**12)],
             "refused before work: bound on scenes", ("--count", "scenes"), timeout=30),
        Case("generate-only-1e12", [*g, "--out", str(fx.path("g-only")), "--only", str(10**12)],
             "refused before work: bound on scene index", ("--only", "scene"), timeout=30),
        Case("generate-num-scenes-0", [*g, "--out", str(fx.path("g0")), "-n", "0"], "refused: at least 1",
             ("--num-scenes",)),
        Case("generate-num-scenes-garbage", [*g, "--out", str(fx.path("g1")), "-n", "lots"], "refused: not an integer",
             ("--num-scenes",)),
        Case("generate-workers-1e6", [*g, "--out", str(fx.path("g-w")), "-n", "1", "--workers", str(10**6)],
             "refused: bound on workers", ("--workers", "workers"), timeout=30),
        Case("generate-no-count", [*g, "--out", str(fx.path("g2"))], "asks for --num-scenes", ("--num-scenes",)),
        Case("generate-backend-unknown", [*g, "--out", str(fx.path("g-be")), "-n", "1", "--backend", "slurm"],
             "refused: unknown backend", ("--backend", "slurm")),
        Case("generate-ray-address-unreachable", [*g, "--out", str(fx.path("g-ray")), "-n", "1", "--backend", "ray",
                                                  "--ray-address", "127.0.0.1:9"],
             "refused within 30 s: unreachable Ray address", ("127.0.0.1:9",), timeout=40),
        Case("generate-ray-address-garbage", [*g, "--out", str(fx.path("g-ray2")), "-n", "1", "--backend", "ray",
                                              "--ray-address", "head:port"],
             "refused: not HOST:PORT", ("head:port",), timeout=40),
        Case("generate-config-missing", ["generate", "--out", str(fx.path("g3")), "-n", "1", "--config",
                                         str(fx.path("nope.yaml"))], "config not found", ("nope.yaml",)),
        Case("generate-config-folder", ["generate", "--out", str(fx.path("g4")), "-n", "1", "--config",
                                        str(fx.root)], "config is a folder", (fx.root.name,)),
        Case("generate-preset-unknown", [*g, "--out", str(fx.path("g5")), "-n", "1", "--preset", "nosuch"],
             "unknown preset, known ones listed", ("nosuch",)),
        Case("generate-preset-escape-codes", [*g, "--out", str(fx.path("g6")), "-n", "1", "--preset", ESC_NAME],
             "unknown preset shown inert", ("pwned",)),
        Case("generate-assets-missing", [*g, "--out", str(fx.path("g7")), "-n", "1", "--assets",
                                         str(fx.path("no-lib"))], "catalog not found", ("no-lib",)),
        Case("generate-assets-is-file", [*g, "--out", str(fx.path("g8")), "-n", "1", "--assets", str(afile)],
             "catalog is a file", ("gen-file",)),
        yaml_case(fx, "yaml-garbage", "\x00\xff\xfe binary \x01", "not valid YAML", ("yaml-garbage",)),
        yaml_case(fx, "yaml-truncated", "selection: {floor_count: 6, wall", "not valid YAML", ("yaml-truncated",)),
        yaml_case(fx, "yaml-list", "- a\n- b\n", "expected a mapping", ("yaml-list",)),
        yaml_case(fx, "yaml-unknown-key", t + "selection2: {}\n", "unknown key", ("selection2",)),
        yaml_case(fx, "yaml-floor-count-1e9", t.replace("floor_count: 6", "floor_count: 1000000000"),
                  "bound on floor_count", ("floor_count",)),
        yaml_case(fx, "yaml-wall-count-1e9", t.replace("wall_count: 2", "wall_count: 1000000000"),
                  "bound on wall_count", ("wall_count",)),
        yaml_case(fx, "yaml-on-top-1e9", t.replace("on_top_count: 1", "on_top_count: 1000000000"),
                  "bound on on_top_count", ("on_top_count",)),
        yaml_case(fx, "yaml-image-1e5", t.replace("width: 80", "width: 100000").replace("height: 60", "height: 100000"),
                  "refused before work: pixels bound or memory estimate", ("width", "height", "pixels")),
        yaml_case(fx, "yaml-image-feasible-not", t.replace("width: 80", "width: 8000").replace("height: 60",
                  "height: 8000").replace("views_per_point: 6", "views_per_point: 360").replace(
                  "vantage_points: 2", "vantage_points: 100"), "refused before work: memory estimate",
                  ("GiB", "memory")),
        yaml_case(fx, "yaml-views-1e6", t.replace("views_per_point: 6", "views_per_point: 1000000"),
                  "bound on views", ("views_per_point",)),
        yaml_case(fx, "yaml-vantage-1e6", t.replace("vantage_points: 2", "vantage_points: 1000000"),
                  "bound on vantage points", ("vantage_points",)),
        yaml_case(fx, "yaml-voxel-1e-9", _set(t, "render", "voxel_size: 1.0e-9"),
                  "bound on voxel_size", ("voxel_size",)),
        yaml_case(fx, "yaml-voxel-0", _set(t, "render", "voxel_size: 0"), "voxel_size must be > 0", ("voxel_size",)),
        yaml_case(fx, "yaml-vantage-cell-1e-9", _set(t, "render", "vantage_cell: 1.0e-9"), "bound on vantage_cell",
                  ("vantage_cell",)),
        yaml_case(fx, "yaml-cell-size-1e-9", _set(t, "layout", "cell_size: 1.0e-9"), "bound on cell_size",
                  ("cell_size",)),
        yaml_case(fx, "yaml-area-1e9", t.replace("area_max: 16.0", "area_max: 1000000000.0"), "bound on area_max",
                  ("area_max",)),
        yaml_case(fx, "yaml-height-inf", _set(t, "room", "height_max: .inf"), "refused: not finite",
                  ("height_max",)),
        yaml_case(fx, "yaml-fx-nan", _set(t, "render", "fx: .nan"), "refused: not a number", ("fx",)),
        yaml_case(fx, "yaml-threads-1e6", _set(t, "render", "threads: 1000000"), "bound on threads", ("threads",)),
        yaml_case(fx, "yaml-rotations-1e9", _set(t, "layout", "rotations: 1000000000"), "bound on rotations",
                  ("rotations",)),
        yaml_case(fx, "yaml-max-nodes-1e12", _set(t, "layout", "max_nodes: 1000000000000"), "bound on max_nodes",
                  ("max_nodes",)),
        yaml_case(fx, "yaml-budget-0", t.replace("group_budget_s: 120.0", "group_budget_s: 0"),
                  "group_budget_s must be > 0", ("group_budget_s",)),
        yaml_case(fx, "yaml-budget-huge", t.replace("group_budget_s: 120.0", "group_budget_s: 1.0e12"),
                  "bound on group_budget_s", ("group_budget_s",)),
        yaml_case(fx, "yaml-llm-timeout-neg", t + "llm: {timeout_s: -1}\n", "timeout_s must be > 0", ("timeout_s",)),
        yaml_case(fx, "yaml-llm-timeout-huge", t + "llm: {timeout_s: 1.0e12}\n", "bound on timeout_s", ("timeout_s",)),
        yaml_case(fx, "yaml-llm-retries-huge", t + "llm: {retries: 1000000000}\n", "bound on retries", ("retries",)),
        yaml_case(fx, "yaml-procedural-1e9", t.replace("procedural_count: 60", "procedural_count: 1000000000"),
                  "bound on procedural_count", ("procedural_count",)),
        yaml_case(fx, "yaml-seed-huge", t.replace("seed: 11", "seed: 100000000000000000000000000000"),
                  "bound on seed", ("seed",)),
        yaml_case(fx, "yaml-seed-negative", t.replace("seed: 11", "seed: -5"), "refused: seeds are 0..2^32-1",
                  ("seed",)),
    ]
    # !!python/object/apply must never run
    marker = fx.path("yaml-marker")
    cases.append(Case("yaml-python-object-apply", ["generate", "--out", str(fx.path("g9")), "-n", "1", "--config",
                                                   str(fx.write("evil.yaml", f"!!python/object/apply:os.system "
                                                                              f"['touch {marker}']\n"))],
                      "refused as YAML, marker not created", ("evil.yaml",), check=marker_check(marker)))
    cases += _generate_existing_dataset_cases(fx, g)
    return cases


def _set(text: str, section: str, line: str) -> str:
    """``text`` (the tiny YAML) with ``line`` added to ``section``."""
    import yaml

    data = yaml.safe_load(text)
    k, v = line.split(":", 1)
    data.setdefault(section, {})[k.strip()] = yaml.safe_load(v)
    return yaml.safe_dump(data)


def _generate_existing_dataset_cases(fx: Fixtures, g: list[str]) -> list[Case]:
    cases: list[Case] = []
    # another seed into an existing dataset: refused, nothing changed
    d1 = fx.copy_base("ds-other-seed")
    cases.append(Case("generate-existing-other-seed", [*g, "--out", str(d1), "-n", "3", "--seed", "99"],
                      "refused: other settings; data kept", (d1.name,), check=unchanged_check(d1, fx.base_digest)))
    # bit rot in a complete scene: regenerated on resume to the same bytes
    d2 = fx.copy_base("ds-bitrot")

    def rot() -> None:
        p = d2 / "scene_000001" / "coord.npy"
        b = bytearray(p.read_bytes())
        b[-5] ^= 0xFF
        p.write_bytes(bytes(b))

    def rot_check(res: Result) -> tuple[str, str] | None:
        gone = lost(fx.base_digest, scene_digest(d2))
        return ("loss", f"not restored: {gone}") if gone else None

    cases.append(Case("generate-resume-bit-rot", [*g, "--out", str(d2), "-n", "2"],
                      "damaged scene regenerated, identical bytes", want="ok", prepare=rot, check=rot_check))
    # a scene folder that is a file
    d3 = fx.copy_base("ds-scene-file")

    def scene_file() -> None:
        (d3 / "scene_000002").write_text("not a folder")

    cases.append(Case("generate-scene-path-is-file", [*g, "--out", str(d3), "-n", "3"],
                      "refused naming the file, data kept", ("scene_000002",), prepare=scene_file,
                      check=unchanged_check(d3, fx.base_digest)))
    # truncated manifest.json in an existing dataset
    d4 = fx.copy_base("ds-bad-manifest")

    def bad_manifest() -> None:
        p = d4 / "manifest.json"
        p.write_bytes(p.read_bytes()[:40])

    cases.append(Case("generate-truncated-manifest", [*g, "--out", str(d4), "-n", "3"],
                      "manifest rebuilt or refused naming it, data kept", ("manifest.json",), want="warn",
                      prepare=bad_manifest, check=unchanged_check(d4, fx.base_digest)))
    cases += _fault_cases(fx, g)
    return cases


def _fault_cases(fx: Fixtures, g: list[str]) -> list[Case]:
    cases: list[Case] = []
    ro = fx.path("ro-dir")
    no_dac = _no_dac()

    def make_ro() -> None:
        ro.mkdir(exist_ok=True)
        ro.chmod(0o555)

    cases.append(Case("generate-out-permission-denied", [*g, "--out", str(ro), "-n", "1"],
                      "permission denied, names the folder", ("ro-dir",), prefix=no_dac, prepare=make_ro,
                      skip=fx.setpriv_ok and f"cannot drop root's permission bypass: {fx.setpriv_ok}"))
    cases.append(Case("generate-out-read-only-fs", [*g, "--out", str(fx.path("rofs", "data")), "-n", "1"],
                      "read-only file system, names the folder", ("rofs",),
                      prepare=lambda: fx.mount_tmpfs("rofs", "1m", read_only=True),
                      skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"))
    # disk full part-way: the complete scenes stay, the message says how many and how to resume;
    # after room is made the re-run gives the reference bytes
    full = fx.path("diskfull")

    def full_runner(case: Case) -> Result:
        fx.mount_tmpfs("diskfull", "1600k")
        res = run_cli(case.argv, fx.env, fx.cwd, case.timeout)
        before = scene_digest(full / "data")
        subprocess.run(["mount", "-o", "remount,size=64m", str(full)], check=True, capture_output=True)
        again = run_cli(case.argv, fx.env, fx.cwd, case.timeout)
        after = scene_digest(full / "data")
        res.err += f"\n[fuzz] re-run after making room: exit {again.rc}\n"
        if lost(before, after) or after != fx.ref4:
            res.err += f"[fuzz] LOSS: {lost(before, after)} / differs from reference: {lost(fx.ref4, after)}\n"
        if again.rc != 0:
            res.err += again.err[-400:]
        return res

    def full_check(res: Result) -> tuple[str, str] | None:
        if "[fuzz] LOSS" in res.err:
            return "loss", res.err.split("[fuzz] LOSS:", 1)[1].strip()[:200]
        if "re-run after making room: exit 0" not in res.err:
            return "unclear", "the re-run after making room failed"
        if res.rc != 0 and not re.search(r"\d+ of 4 scenes complete .*re-run the same command to resume",
                                         " ".join(res.err.split())):
            return "unclear", "does not say how many scenes are complete and how to resume"
        return None

    cases.append(Case("generate-disk-full", [*g, "--out", str(full / "data"), "-n", "4"],
                      "no space: N of 4 complete, re-run resumes to identical bytes", ("No space", "no space"),
                      runner=full_runner, check=full_check, timeout=90,
                      skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"))
    cases.append(_sigterm_case(fx, g))
    cases.append(_concurrent_case(fx, g))
    return cases


def _sigterm_case(fx: Fixtures, g: list[str]) -> Case:
    out = fx.path("sigterm", "data")

    def runner(case: Case) -> Result:
        cmd = [sys.executable, "-m", "assist3d", *case.argv]
        t0 = time.monotonic()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=fx.env, cwd=fx.cwd,
                                start_new_session=True)
        deadline = time.monotonic() + 60
        while proc.poll() is None and time.monotonic() < deadline and not list(out.glob("scene_*/meta.json")):
            time.sleep(0.02)
        procs = descendants(proc.pid)
        proc.send_signal(signal.SIGTERM)
        try:
            o, e = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            kill_group(proc.pid)
            o, e = proc.communicate()
            return Result(proc.returncode, o.decode(), e.decode(), time.monotonic() - t0, True)
        alive = survivors(procs)
        note = f"\n[fuzz] {len(procs)} processes below the run, {len(alive)} alive after it\n"
        for pid in alive:
            os.kill(pid, signal.SIGKILL)  # started by this case
        again = run_cli(case.argv, fx.env, fx.cwd, 120)
        note += f"[fuzz] re-run exit {again.rc}; identical to reference: {scene_digest(out) == fx.ref4}\n"
        return Result(proc.returncode, o.decode(), e.decode() + note, time.monotonic() - t0, False)

    def check(res: Result) -> tuple[str, str] | None:
        if not re.search(r"0 alive after it", res.err):
            return "hang", "worker processes outlived the run"
        if "identical to reference: True" not in res.err:
            return "loss", "the re-run did not give the reference bytes"
        if res.rc != 143:
            return "unclear", f"exit {res.rc}, expected 143"
        return None

    return Case("generate-sigterm-workers-2", [*g, "--out", str(out), "-n", "4", "--workers", "2"],
                "exit 143, one line 'N of 4 complete', no survivors, re-run identical", ("interrupted",),
                runner=runner, check=check, timeout=120)


def _concurrent_case(fx: Fixtures, g: list[str]) -> Case:
    out = fx.path("concurrent", "data")

    def runner(case: Case) -> Result:
        cmd = [sys.executable, "-m", "assist3d", *case.argv]
        t0 = time.monotonic()
        procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=fx.env, cwd=fx.cwd,
                                  start_new_session=True) for _ in range(2)]
        outs = [p.communicate(timeout=120) for p in procs]
        rcs = sorted(p.returncode for p in procs)
        err = "".join(e.decode() for _, e in outs)
        again = run_cli(case.argv, fx.env, fx.cwd, 120)
        err += f"\n[fuzz] exits {rcs}; re-run exit {again.rc}; identical: {scene_digest(out) == fx.ref4}\n"
        rc = 0 if rcs == [0, 0] else max(rcs)
        return Result(rc, "".join(o.decode() for o, _ in outs), err, time.monotonic() - t0, False)

    def check(res: Result) -> tuple[str, str] | None:
        if "identical: True" not in res.err:
            return "loss", "the dataset differs from the reference"
        if res.rc != 0 and "another" not in res.err:
            return "unclear", "the refused run does not say another run holds the folder"
        return None

    return Case("generate-two-runs-one-folder", [*g, "--out", str(out), "-n", "4"],
                "one run refused ('another ... is writing'), data identical", ("another",), want="warn",
                runner=runner, check=check, timeout=120)


def layout_cases(fx: Fixtures) -> list[Case]:
    lay = ["layout", "--config", str(fx.tiny), "--no-glb"]
    lib = ["--assets", str(fx.proc_lib)]
    afile = fx.write("lay-file", "x")
    return [
        Case("layout-out-is-file", [*lay, "--out", str(afile)], "refused: not a folder", ("lay-file",)),
        Case("layout-out-under-file", [*lay, "--out", str(afile / "x")], "refused: a parent is a file", ("lay-file",)),
        Case("layout-seed-negative", [*lay, "--out", str(fx.path("l1")), "--seed", "-3"],
             "refused: seeds are 0..2^32-1", ("--seed",)),
        Case("layout-seed-huge", [*lay, "--out", str(fx.path("l2")), "--seed", str(10**30)],
             "bound on seed", ("--seed", "seed")),
        Case("layout-scene-index-negative", [*lay, "--out", str(fx.path("l3")), "--scene-index", "-1"],
             "refused: index >= 0", ("--scene-index",)),
        Case("layout-assets-empty-folder", [*lay, "--out", str(fx.path("l4")), "--assets",
                                            str(fx.path("empty-lib-dir", "x").parent)],
             "catalog empty or missing", ("empty-lib-dir",),
             prepare=lambda: fx.path("empty-lib-dir", "x").parent.mkdir(exist_ok=True)),
        Case("layout-assets-garbage-index", [*lay, "--out", str(fx.path("l5")), "--assets",
                                             str(fx.path("bad-lib", "index.json").parent)],
             "catalog index unreadable", ("index.json",),
             prepare=lambda: fx.write("bad-lib/index.json", "{\"assets\": [tru")),
        Case("layout-llm-refused-connection", [*lay, "--out", str(fx.path("l6")), "--llm-base-url",
                                               "http://127.0.0.1:9/v1", "--llm-model", "m"],
             "falls back to rules with a warning", ("127.0.0.1",), want="warn", timeout=90),
        Case("layout-png-missing", ["layout-png", str(fx.path("none.json")), "--out", str(fx.path("p.png")), *lib],
             "layout file not found", ("none.json",)),
        Case("layout-png-garbage", ["layout-png", str(fx.write("garbage.json", "\x00\x01{[")), "--out",
                                    str(fx.path("p.png")), *lib], "not a readable layout.json", ("garbage.json",)),
        Case("layout-png-truncated", ["layout-png", str(fx.write("trunc.json", fx.layout.read_text()[:300])),
                                      "--out", str(fx.path("p.png")), *lib], "not a readable layout.json",
             ("trunc.json",)),
        Case("layout-png-is-folder", ["layout-png", str(fx.root / "gt"), "--out", str(fx.path("p.png")), *lib],
             "a folder, not a layout.json", ("gt",)),
        Case("layout-png-nan-pose", ["layout-png", str(fx.write("nan.json", _nan_layout(fx.layout))), "--out",
                                     str(fx.path("nan.png")), *lib], "refused: non-finite pose", ("nan.json",)),
        Case("layout-png-out-is-folder", ["layout-png", str(fx.layout), "--out", str(fx.root / "gt"), *lib],
             "refused: --out is a folder", ("gt",)),
        Case("layout-png-out-under-file", ["layout-png", str(fx.layout), "--out", str(afile / "p.png"), *lib],
             "refused: a parent is a file", ("lay-file",)),
        _devfull_case(fx, "layout-png-dev-full", ["layout-png", str(fx.layout), *lib, "--out"]),
    ]


def _nan_layout(path: Path) -> str:
    data = json.loads(path.read_text())
    text = json.dumps(data)
    inst = data.get("instances") or []
    if inst and "pose" in inst[0]:
        inst[0]["pose"][0][3] = float("nan")
        text = json.dumps(data)
    return text


def _devfull_case(fx: Fixtures, name: str, argv: list[str]) -> Case:
    """The output path is a /dev/full device node (made in the temporary folder). An atomic writer
    never writes into its target (the temporary file is beside it) and, running as root, would
    rename the finished file over the device: outputs that are devices are refused instead."""
    node = fx.path(f"{name}-full.png")

    def make_node() -> None:
        os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 7))

    def check(res: Result) -> tuple[str, str] | None:
        if not node.is_char_device():
            return "loss", "the device node was replaced"
        return None

    return Case(name, [*argv, str(node)], "refused: not a regular file; the device stays", ("full",),
                prepare=make_node, check=check,
                skip=None if fx.devfull else "mknod is not permitted (no /dev/full-like node)")


def show_cases(fx: Fixtures) -> list[Case]:
    afile = fx.write("show-file", "x")
    d = fx.copy_base("show-trunc")
    p = d / "scene_000000" / "coord.npy"
    p.write_bytes(p.read_bytes()[:100])
    return [
        Case("show-missing", ["show", str(fx.path("nothing"))], "not found", ("nothing",)),
        Case("show-empty-folder", ["show", str(fx.path("empty", "x").parent)], "no scene found", ("empty",),
             prepare=lambda: fx.path("empty", "x").parent.mkdir(exist_ok=True)),
        Case("show-a-file", ["show", str(afile)], "not a scene folder", ("show-file",)),
        Case("show-truncated-scene", ["show", str(d), "--out", str(fx.path("s.png"))], "truncated array named",
             ("coord.npy",)),
        Case("show-scene-path-escape", ["show", str(fx.base), "--scene", "../../gt", "--out", str(fx.path("s2.png"))],
             "refused: scene id leaves the folder", ("../../gt",)),
        Case("show-scene-escape-codes", ["show", str(fx.base), "--scene", ESC_NAME, "--out", str(fx.path("s3.png"))],
             "not found, shown inert", ("pwned",)),
        Case("show-out-under-file", ["show", str(fx.base), "--out", str(afile / "x.png")],
             "refused: a parent is a file", ("show-file",)),
        Case("show-out-is-folder", ["show", str(fx.base), "--out", str(fx.root / "gt")], "refused: a folder",
             ("gt",)),
        Case("show-out-disk-full", ["show", str(fx.base), "--out", str(fx.path("sfull", "p.png"))],
             "no space left, names the file", ("sfull",),
             prepare=lambda: fx.full_tmpfs("sfull"), skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"),
        Case("show-out-permission-denied", ["show", str(fx.base), "--out", str(fx.path("ro-show", "p.png"))],
             "permission denied, names the file", ("ro-show",), prefix=_no_dac(),
             prepare=lambda: (fx.path("ro-show", "x").parent.mkdir(exist_ok=True),
                              fx.path("ro-show", "x").parent.chmod(0o555)),
             skip=fx.setpriv_ok and f"cannot drop root's permission bypass: {fx.setpriv_ok}"),
    ]


def bench_cases(fx: Fixtures) -> list[Case]:
    afile = fx.write("bench-file", "x")
    return [
        Case("bench-scenes-1e9", ["bench", "--scenes", str(10**9), "--json"], "refused before work: bound",
             ("--scenes",), timeout=30),
        Case("bench-scenes-0", ["bench", "--scenes", "0"], "refused: at least 1", ("--scenes",)),
        Case("bench-keep-is-file", ["bench", "--scenes", "1", "--keep", str(afile)], "refused: not a folder",
             ("bench-file",), timeout=30),
        Case("bench-assets-missing", ["bench", "--scenes", "1", "--assets", str(fx.path("no-lib2"))],
             "catalog not found", ("no-lib2",), timeout=30),
    ]


def assets_cases(fx: Fixtures) -> list[Case]:
    afile = fx.write("assets-file", "x")
    lib = fx.path("lib-meshes")
    outside = fx.write("outside.obj", _box_obj())
    bad_manifest = fx.write("escape.csv", "path,class,groups,size\n../outside.obj,box,floor,\"1,1,1\"\n")
    trunc = fx.meshes / "trunc.obj"
    trunc.write_text(_box_obj()[:-7])  # cut inside the last face line
    trunc_manifest = fx.write("trunc.csv", "path,class,groups,size\ntrunc.obj,box,floor,\"1,1,1\"\n")
    esc_manifest = fx.write("escname.csv", f"path,class,groups,size\nbox.obj,{ESC_NAME},floor,\"1,1,1\"\n")
    del outside
    proc_lib = fx.proc_lib
    return [
        Case("assets-stats-missing-library", ["assets", "stats", "--library", str(fx.path("nolib"))],
             "catalog not found", ("nolib",)),
        Case("assets-stats-library-is-file", ["assets", "stats", "--library", str(afile)], "not a catalog folder",
             ("assets-file",)),
        Case("assets-stats-garbage-index", ["assets", "stats", "--library", str(fx.path("bad-lib2", "x").parent)],
             "index unreadable", ("index.json",), prepare=lambda: fx.write("bad-lib2/index.json", "\x00garbage")),
        Case("assets-list-limit-negative", ["assets", "list", "--limit", "-1"], "refused: >= 0", ("--limit",)),
        Case("assets-procedural-count-1e9", ["assets", "procedural", "--count", str(10**9), "--library",
                                             str(fx.path("lib-big"))], "refused before work: bound", ("--count",),
             timeout=30),
        Case("assets-procedural-workers-neg", ["assets", "procedural", "--count", "5", "--workers", "-3",
                                               "--library", str(fx.path("lib-w"))], "refused: workers >= 0",
             ("--workers",)),
        Case("assets-procedural-workers-1e6", ["assets", "procedural", "--count", "5", "--workers", str(10**6),
                                               "--library", str(fx.path("lib-w2"))], "refused: bound on workers",
             ("--workers",), timeout=30),
        Case("assets-procedural-library-is-file", ["assets", "procedural", "--count", "5", "--workers", "1",
                                                   "--library", str(afile)], "refused: not a folder",
             ("assets-file",)),
        Case("assets-procedural-disk-full", ["assets", "procedural", "--count", "20", "--workers", "1", "--library",
                                             str(fx.path("afull", "lib"))], "no space left, names the folder",
             ("afull",), prepare=lambda: fx.full_tmpfs("afull", ("lib",)), timeout=60,
             skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"),
        Case("assets-procedural-read-only-fs", ["assets", "procedural", "--count", "5", "--workers", "1",
                                                "--library", str(fx.path("arofs", "lib"))], "read-only file system",
             ("arofs",), prepare=lambda: fx.mount_tmpfs("arofs", "1m", read_only=True),
             skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"),
        Case("import-meshes-missing-folder", ["assets", "import", "meshes", str(fx.path("nomesh")), "--manifest",
                                              str(fx.manifest), "--library", str(lib), "--workers", "1"],
             "folder not found", ("nomesh",)),
        Case("import-meshes-folder-is-file", ["assets", "import", "meshes", str(afile), "--manifest",
                                              str(fx.manifest), "--library", str(lib), "--workers", "1"],
             "not a folder", ("assets-file",)),
        Case("import-meshes-manifest-missing", ["assets", "import", "meshes", str(fx.meshes), "--manifest",
                                                str(fx.path("none.csv")), "--library", str(lib), "--workers", "1"],
             "manifest not found", ("none.csv",)),
        Case("import-meshes-manifest-garbage", ["assets", "import", "meshes", str(fx.meshes), "--manifest",
                                                str(fx.write("garbage.json", b"\x00\xff{")), "--library", str(lib),
                                                "--workers", "1"], "manifest unreadable", ("garbage.json",)),
        Case("import-meshes-path-escape", ["assets", "import", "meshes", str(fx.meshes), "--manifest",
                                           str(bad_manifest), "--library", str(lib), "--workers", "1", "--json"],
             "row refused: path leaves the folder", ("outside",), want="warn", check=_no_import_of("outside", lib)),
        Case("import-meshes-truncated-obj", ["assets", "import", "meshes", str(fx.meshes), "--manifest",
                                             str(trunc_manifest), "--library", str(fx.path("lib-trunc")),
                                             "--workers", "1"], "skipped or imported with a warning",
             ("trunc.obj",), want="warn", owner="readers"),
        Case("import-meshes-escape-class", ["assets", "import", "meshes", str(fx.meshes), "--manifest",
                                            str(esc_manifest), "--library", str(fx.path("lib-esc")), "--workers",
                                            "1"], "imported, the class name shown inert", ("pwned", "class"),
             want="ok"),
        Case("import-sh3d-missing", ["assets", "import", "sh3d", str(fx.path("none.sh3f")), "--library",
                                     str(fx.path("lib-sh3d")), "--workers", "1"], "not found", ("none.sh3f",)),
        Case("import-sh3d-garbage", ["assets", "import", "sh3d", str(fx.write("bad.sh3f", b"PK\x03\x04garbage")),
                                     "--library", str(fx.path("lib-sh3d2")), "--workers", "1"],
             "not a readable catalog", ("bad.sh3f",)),
        Case("cluster-assets-k-0", ["cluster-assets", "--library", str(proc_lib), "--k", "0"],
             "refused: k >= 1", ("--k",)),
        Case("cluster-assets-k-1e9", ["cluster-assets", "--library", str(proc_lib), "--k", str(10**9)], "refused: bound on k", ("--k",),
             timeout=40),
        Case("cluster-assets-missing-library", ["cluster-assets", "--library", str(fx.path("nolib3"))],
             "catalog not found", ("nolib3",)),
    ]


def _says(words: str) -> Callable[[Result], tuple[str, str] | None]:
    """A failed run whose message does not say ``words`` (the way forward) is unclear."""
    def check(res: Result) -> tuple[str, str] | None:
        if res.rc not in (0, None) and "Traceback" not in res.text and words not in _squash(res.err):
            return "unclear", f"the message does not say {words!r}"
        return None

    return check


def _no_import_of(word: str, lib: Path) -> Callable[[Result], tuple[str, str] | None]:
    def check(res: Result) -> tuple[str, str] | None:
        index = lib / "index.json"
        if index.is_file() and word in index.read_text() and '"assets": []' not in index.read_text():
            data = json.loads(index.read_text())
            if any(word in str(a.get("path", "")) or word in str(a.get("name", "")) for a in data.get("assets", [])):
                return "escape", f"a mesh outside the folder was imported ({word})"
        return None

    return check


def evaluate_cases(fx: Fixtures) -> list[Case]:
    ev = ["evaluate", "--gt", f"array:{fx.gt}"]
    afile = fx.write("eval-file", "x")
    garbage = fx.write("ev-garbage/scan.npz", b"\x00garbage")
    trunc = fx.path("ev-trunc/scan.npz")
    trunc.write_bytes((fx.preds / "scan.npz").read_bytes()[:200])
    shape = fx.path("ev-shape/scan.npz")
    np.savez(shape, masks=np.ones((2, 7), bool), scores=np.ones(2, np.float32))
    out_txt = fx.path("ev-escape/scan.txt")
    n = len(np.load(fx.scan))
    (out_txt.parent.parent / "outside_mask.txt").write_text("".join("1\n" for _ in range(n)))
    out_txt.write_text("../outside_mask.txt 1 0.9\n")
    nan_gt = fx.path("ev-nan-gt/scan.npy")
    a = np.load(fx.scan)
    a[:10, :3] = np.nan
    np.save(nan_gt, a)
    esc_gt = fx.path("ev-esc-gt", f"scan{ESC_NAME}.npy")
    np.save(esc_gt, np.load(fx.scan))
    lbl = fx.path("ev-label-gt/scan.npy")
    b = np.load(fx.scan)
    b[:, 7] += 0.5
    np.save(lbl, b)
    empty_gt = fx.path("ev-empty-gt/scan.npy")
    np.save(empty_gt, np.zeros((0, 8), np.float32))
    return [
        Case("evaluate-gt-unknown-format", ["evaluate", "--gt", "scanet:/x", "--pred", str(fx.preds)],
             "unknown format, did you mean", ("scanet",)),
        Case("evaluate-gt-missing", ["evaluate", "--gt", f"array:{fx.path('nogt')}", "--pred", str(fx.preds)],
             "not found", ("nogt",)),
        Case("evaluate-gt-garbage", ["evaluate", "--gt", f"array:{fx.write('gtg/scan.npy', b'garbage')}",
                                     "--pred", str(fx.preds)], "not a readable array", ("scan.npy",)),
        Case("evaluate-gt-nonfinite", ["evaluate", "--gt", f"array:{nan_gt.parent}", "--pred", str(fx.preds)],
             "refused or cleaned with a warning", ("finite", "NaN", "nan"), want="warn", owner="readers"),
        Case("evaluate-gt-non-integer-labels", ["evaluate", "--gt", f"array:{lbl.parent}", "--pred", str(fx.preds)],
             "refused or cleaned with a warning", ("integer",), want="warn", owner="readers"),
        Case("evaluate-gt-empty-scan", ["evaluate", "--gt", f"array:{empty_gt.parent}", "--pred", str(fx.preds),
                                        "--allow-missing"], "refused: no points", ("no points", "empty"),
             owner="readers"),
        Case("evaluate-gt-escape-name", ["evaluate", "--gt", f"array:{esc_gt.parent}", "--pred", str(fx.preds),
                                         "--per-scene"], "missing prediction, name shown inert", ("pwned",)),
        Case("evaluate-pred-missing", [*ev, "--pred", str(fx.path("nopred"))], "prediction folder not found",
             ("nopred",)),
        Case("evaluate-pred-is-file", [*ev, "--pred", str(afile)], "not a folder", ("eval-file",)),
        Case("evaluate-pred-garbage-npz", [*ev, "--pred", str(garbage.parent)], "cannot read", ("scan.npz",)),
        Case("evaluate-pred-truncated-npz", [*ev, "--pred", str(trunc.parent)], "cannot read", ("scan.npz",)),
        Case("evaluate-pred-wrong-shape", [*ev, "--pred", str(shape.parent)], "wrong number of points",
             ("scan.npz",)),
        Case("evaluate-pred-path-escape", [*ev, "--pred", str(out_txt.parent)], "refused: leads outside",
             ("outside",)),
        Case("evaluate-workers-1e6", [*ev, "--pred", str(fx.preds), "--workers", str(10**6)],
             "refused: bound on workers", ("--workers",), timeout=30),
        Case("evaluate-feature-not-importable", [*ev, "--pred", str(fx.preds), "--ood-reference", f"array:{fx.gt}",
                                                 "--feature", "nosuchmodule:fn"], "cannot import", ("nosuchmodule",)),
        Case("convert-src-missing", ["convert-predictions", str(fx.path("nosrc")), str(fx.path("dst")), "--to",
                                     "txt"], "not found", ("nosrc",)),
        Case("convert-to-bad", ["convert-predictions", str(fx.preds), str(fx.path("dst2")), "--to", "csv"],
             "expected txt or npz", ("--to",)),
        Case("convert-dst-is-file", ["convert-predictions", str(fx.preds), str(afile), "--to", "txt"],
             "refused: not a folder", ("eval-file",)),
        Case("convert-src-garbage", ["convert-predictions", str(garbage.parent), str(fx.path("dst3")), "--to",
                                     "txt"], "cannot read", ("scan.npz",)),
        Case("convert-dst-disk-full", ["convert-predictions", str(fx.preds), str(fx.path("cfull", "dst")), "--to",
                                       "txt"], "no space left", ("cfull",),
             prepare=lambda: fx.full_tmpfs("cfull", ("dst",)),
             skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"),
    ]


def metrics_cases(fx: Fixtures) -> list[Case]:
    afile = fx.write("metrics-file", "x")
    m = ["metrics", str(fx.base)]
    return [
        Case("metrics-missing-dataset", ["metrics", str(fx.path("nods"))], "not found", ("nods",)),
        Case("metrics-bad-spec", ["metrics", "foo:bar:baz"], "unknown format", ("foo",)),
        Case("metrics-empty-folder", ["metrics", str(fx.path("mempty", "x").parent)], "no scenes",
             ("mempty",), prepare=lambda: fx.path("mempty", "x").parent.mkdir(exist_ok=True)),
        Case("metrics-codebook-garbage", [*m, "--codebook", str(fx.write("cb.npz", b"garbage"))],
             "codebook unreadable", ("cb.npz",)),
        Case("metrics-codebook-missing", [*m, "--codebook", str(fx.path("nocb.npz"))], "codebook not found",
             ("nocb.npz",)),
        Case("metrics-max-scenes-negative", [*m, "--max-scenes", "-1"], "refused: >= 1", ("--max-scenes",)),
        Case("metrics-max-scenes-1e12", [*m, "--max-scenes", str(10**12), "--json"], "refused: bound",
             ("--max-scenes",)),
        Case("metrics-plot-under-file", [*m, "--plot", str(afile / "p.png")], "refused: a parent is a file",
             ("metrics-file",)),
        Case("metrics-save-codebook-is-folder", [*m, "--save-codebook", str(fx.root / "gt")],
             "refused: a folder", ("gt",)),
        _devfull_case(fx, "metrics-plot-dev-full", [*m, "--plot"]),
        Case("metrics-nonfinite-array", ["metrics", f"array:{fx.path('ev-nan-gt/scan.npy')}"],
             "refused or cleaned with a warning", ("finite", "NaN", "nan"), want="warn", owner="readers"),
    ]


def train_cases(fx: Fixtures) -> list[Case]:
    afile = fx.write("train-file", "x")
    marker = fx.path("train-marker")
    marker2 = fx.path("predict-marker")
    marker3 = fx.path("resume-marker")
    t = ["train", "--config", str(fx.train_cfg), "--data", f"assist3d:{fx.base}", "--device", "cpu"]
    evil_yaml = fx.write("evil-train.yaml", f"!!python/object/apply:os.system ['touch {marker}']\n")
    evil_pt = evil_checkpoint(fx.path("evil.pt"), marker2, torch_format=True)
    evil_raw = evil_checkpoint(fx.path("evil-raw.pt"), marker2, torch_format=False)
    resume_dir = fx.path("resume-evil")
    evil_checkpoint(resume_dir / "last.pt", marker3, torch_format=True)
    trunc = fx.path("trunc.pt")
    trunc.write_bytes(fx.ckpt.read_bytes()[:5000])
    p = ["predict", "--data", f"array:{fx.gt}", "--device", "cpu"]
    pc = [*p, "--checkpoint", str(fx.ckpt)]
    return [
        Case("train-config-missing", ["train", "--config", str(fx.path("none.yaml"))], "not found", ("none.yaml",)),
        Case("train-config-empty", ["train", "--config", str(fx.write("empty.yaml", "")), "--out",
                                    str(fx.path("t0"))], "no training data", ("training data", "--data")),
        Case("train-config-garbage", ["train", "--config", str(fx.write("tg.yaml", "\x00\x01: [")), "--out",
                                      str(fx.path("t1"))], "not valid YAML", ("tg.yaml",)),
        Case("train-config-python-apply", ["train", "--config", str(evil_yaml), "--out", str(fx.path("t2"))],
             "refused, marker not created", ("evil-train.yaml",), check=marker_check(marker)),
        Case("train-data-missing", ["train", "--config", str(fx.train_cfg), "--data", f"assist3d:{fx.path('nod')}",
                                    "--out", str(fx.path("t3"))], "not found", ("nod",)),
        Case("train-out-is-file", [*t, "--out", str(afile)], "refused: not a folder", ("train-file",), timeout=90),
        Case("train-out-under-file", [*t, "--out", str(afile / "o")], "refused: a parent is a file",
             ("train-file",), timeout=90),
        Case("train-epochs-1e12", [*t, "--out", str(fx.path("t4")), "--epochs", str(10**12)],
             "refused before work: bound on epochs", ("--epochs", "epochs"), timeout=40),
        Case("train-batch-1e9", ["train", "--config", str(fx.write("tb.yaml", fx.train_cfg.read_text().replace(
            "batch_size: 2", "batch_size: 1000000000"))), "--data", f"assist3d:{fx.base}", "--out",
            str(fx.path("t5"))], "bound on batch_size", ("batch_size",), timeout=40),
        Case("train-voxel-1e-9", ["train", "--config", str(fx.write("tv.yaml", fx.train_cfg.read_text().replace(
            "voxel_size: 0.1", "voxel_size: 1.0e-09"))), "--data", f"assist3d:{fx.base}", "--out",
            str(fx.path("t6"))], "bound on voxel_size", ("voxel_size",), timeout=40),
        Case("train-out-disk-full", [*t, "--out", str(fx.path("tfull", "o"))], "no space left; re-run with --resume",
             ("tfull",), prepare=lambda: fx.full_tmpfs("tfull", ("o",)), timeout=90,
             check=_says("--resume"), skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"),
        Case("train-device-bogus", [*t, "--out", str(fx.path("t7")), "--device", "tpu9"], "unknown device",
             ("tpu9",), timeout=40),
        Case("train-resume-evil-checkpoint", [*t, "--out", str(resume_dir), "--resume"],
             "not a safe checkpoint, marker not created", ("last.pt",), check=marker_check(marker3), timeout=60),
        Case("predict-evil-checkpoint", [*p, "--checkpoint", str(evil_pt), "--out", str(fx.path("pe"))],
             "not a safe checkpoint, marker not created", ("evil.pt",), check=marker_check(marker2)),
        Case("predict-evil-raw-pickle", [*p, "--checkpoint", str(evil_raw), "--out", str(fx.path("pe2"))],
             "not a safe checkpoint, marker not created", ("evil-raw.pt",), check=marker_check(marker2)),
        Case("predict-checkpoint-missing", [*p, "--checkpoint", str(fx.path("no.pt")), "--out", str(fx.path("p0"))],
             "not found", ("no.pt",)),
        Case("predict-checkpoint-truncated", [*p, "--checkpoint", str(trunc), "--out", str(fx.path("p1"))],
             "not a readable checkpoint", ("trunc.pt",)),
        Case("predict-checkpoint-folder", [*p, "--checkpoint", str(fx.root), "--out", str(fx.path("p2"))],
             "a folder, not a checkpoint", (fx.root.name,)),
        Case("predict-out-is-file", [*pc, "--out", str(afile)], "refused: not a folder", ("train-file",)),
        Case("predict-top-k-negative", [*pc, "--out", str(fx.path("p3")), "--top-k", "-5"], "refused: >= 0",
             ("--top-k",)),
        Case("predict-top-k-1e12", [*pc, "--out", str(fx.path("p4")), "--top-k", str(10**12)],
             "refused: bound on top-k", ("--top-k",)),
        Case("predict-data-garbage", ["predict", "--checkpoint", str(fx.ckpt), "--data", "garbage", "--out",
                                      str(fx.path("p5"))], "expected FORMAT:PATH", ("garbage",)),
        Case("predict-out-disk-full", [*pc, "--out", str(fx.path("pfull", "o"))], "no space left", ("pfull",),
             prepare=lambda: fx.full_tmpfs("pfull", ("o",)),
             skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"),
        Case("model-bench-points-1e12", ["model-bench", "--points", str(10**12)], "refused before work: bound",
             ("--points",), timeout=40),
        Case("model-bench-points-0", ["model-bench", "--points", "0"], "refused: >= 1", ("--points",)),
        Case("model-bench-repeats-1e9", ["model-bench", "--points", "1000", "--repeats", str(10**9)],
             "refused: bound on repeats", ("--repeats",), timeout=40),
        Case("model-bench-backend-bogus", ["model-bench", "--backend", "cuda9"], "expected torch or spconv",
             ("cuda9",)),
        Case("model-bench-config-garbage", ["model-bench", "--config", str(fx.write("mb.yaml", "[[["))],
             "not valid YAML", ("mb.yaml",)),
    ]


def probe_cases(fx: Fixtures) -> list[Case]:
    marker = fx.path("probe-marker")
    pr = ["probe", "--train", f"assist3d:{fx.base}", "--eval", f"array:{fx.gt}", "--config", str(fx.seg_cfg),
          "--threads", "1"]
    afile = fx.write("probe-file", "x")
    return [
        Case("probe-train-missing", ["probe", "--train", f"assist3d:{fx.path('nope')}", "--eval", f"array:{fx.gt}",
                                     "--steps", "1", "--out", str(fx.path("pr0"))], "not found", ("nope",)),
        Case("probe-eval-garbage-spec", ["probe", "--train", f"assist3d:{fx.base}", "--eval", "::", "--steps", "1",
                                         "--out", str(fx.path("pr1"))], "expected FORMAT:PATH", ("::",)),
        Case("probe-steps-0", [*pr, "--steps", "0", "--out", str(fx.path("pr2"))], "refused: >= 1", ("steps",)),
        Case("probe-steps-negative", [*pr, "--steps", "-4", "--out", str(fx.path("pr3"))], "refused: >= 1",
             ("steps",)),
        Case("probe-steps-1e12", [*pr, "--steps", str(10**12), "--out", str(fx.path("pr4"))],
             "refused before work: bound on steps", ("steps",), timeout=40),
        Case("probe-minutes-negative", [*pr, "--minutes", "-1", "--out", str(fx.path("pr5"))], "refused: > 0",
             ("minutes",)),
        Case("probe-minutes-huge", [*pr, "--minutes", "1e12", "--out", str(fx.path("pr6"))],
             "refused: bound on minutes", ("minutes",), timeout=40),
        Case("probe-config-python-apply", [*pr[:-4], "--config", str(fx.write(
            "evil-seg.yaml", f"!!python/object/apply:os.system ['touch {marker}']\n")), "--steps", "1", "--out",
            str(fx.path("pr7"))], "refused, marker not created", ("evil-seg.yaml",), check=marker_check(marker)),
        Case("probe-out-is-file", [*pr, "--steps", "1", "--out", str(afile)], "refused: not a folder",
             ("probe-file",), timeout=90),
        Case("probe-out-disk-full", [*pr, "--steps", "1", "--out", str(fx.path("prfull", "o"))],
             "no space left; re-run to resume", ("prfull",), prepare=lambda: fx.full_tmpfs("prfull", ("o",)),
             timeout=90, check=_says("resume"), skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"),
        Case("probe-seeds-0", [*pr, "--steps", "1", "--seeds", "0"], "refused: >= 1", ("--seeds",)),
    ]


def segment_cases(fx: Fixtures) -> list[Case]:
    afile = fx.write("seg-file", "x")
    marker = fx.path("segment-marker")
    evil_pt = evil_checkpoint(fx.path("evil-seg.pt"), marker, torch_format=True)
    sg = ["segment", "--method", "geometric"]
    np.save(fx.path("seg-nan.npy"), np.full((50, 3), np.nan, np.float32))
    some_nan = np.load(fx.scan)[:, :6].copy()
    some_nan[:20, 0] = np.inf
    np.save(fx.path("seg-somenan.npy"), some_nan)
    esc = fx.path(f"seg{ESC_NAME}.npy")
    np.save(esc, np.load(fx.scan)[:, :3])
    trunc = fx.path("seg-trunc.npy")
    trunc.write_bytes(fx.scan.read_bytes()[:300])
    np.save(fx.path("seg-str.npy"), np.array([["a", "b", "c"]]))
    return [
        Case("segment-input-missing", [*sg, str(fx.path("none.ply")), "--out", str(fx.path("so0"))], "not found",
             ("none.ply",)),
        Case("segment-input-empty-ply", [*sg, str(fx.write("empty.ply", "")), "--out", str(fx.path("so1"))],
             "not a PLY", ("empty.ply",)),
        Case("segment-input-garbage-ply", [*sg, str(fx.write("garb.ply", b"ply\nformat binary_little_endian 1.0\n"
                                                                          b"element vertex 99999999999\nend_header\n")),
                                           "--out", str(fx.path("so2"))], "truncated PLY", ("garb.ply",)),
        Case("segment-input-truncated-npy", [*sg, str(trunc), "--out", str(fx.path("so3"))], "not readable",
             ("seg-trunc.npy",)),
        Case("segment-input-strings-npy", [*sg, str(fx.path("seg-str.npy")), "--out", str(fx.path("so4"))],
             "expected numeric", ("seg-str.npy",)),
        Case("segment-input-all-nan", [*sg, str(fx.path("seg-nan.npy")), "--out", str(fx.path("so5"))],
             "no finite point", ("seg-nan",)),
        Case("segment-input-some-inf", [*sg, str(fx.path("seg-somenan.npy")), "--out", str(fx.path("so6"))],
             "segmented with a warning: 20 points dropped", ("non-finite",), want="warn"),
        Case("segment-input-escape-name", [*sg, str(esc), "--out", str(fx.path("so7"))],
             "segmented, the name shown inert", ("pwned",), want="ok"),
        Case("segment-input-folder", [*sg, str(fx.root / "gt"), "--out", str(fx.path("so8"))],
             "a folder: give FORMAT:PATH", ("FORMAT:PATH",)),
        Case("segment-evil-checkpoint", ["segment", str(fx.scan), "--checkpoint", str(evil_pt), "--out",
                                         str(fx.path("so9"))], "not a safe checkpoint, marker not created",
             ("evil-seg.pt",), check=marker_check(marker)),
        Case("segment-checkpoint-garbage", ["segment", str(fx.scan), "--checkpoint", str(fx.write("g.pt", "garbage")),
                                            "--out", str(fx.path("so10"))], "not a readable checkpoint", ("g.pt",)),
        Case("segment-out-is-file", [*sg, str(fx.scan), "--out", str(afile)], "refused: not a folder",
             ("seg-file",)),
        Case("segment-out-under-file", [*sg, str(fx.scan), "--out", str(afile / "o")], "refused: a parent is a file",
             ("seg-file",)),
        Case("segment-method-bogus", ["segment", str(fx.scan), "--method", "magic", "--out", str(fx.path("so11"))],
             "expected learned or geometric", ("magic",)),
        Case("segment-threads-1e6", [*sg, str(fx.scan), "--threads", str(10**6), "--out", str(fx.path("so12"))],
             "refused: bound on threads", ("--threads",)),
        Case("segment-out-disk-full", [*sg, str(fx.scan), "--out", str(fx.path("sgfull", "o"))], "no space left",
             ("sgfull",), prepare=lambda: fx.full_tmpfs("sgfull", ("o",)),
             skip=fx.tmpfs_ok and f"cannot mount a tmpfs: {fx.tmpfs_ok}"),
        Case("segment-out-permission-denied", [*sg, str(fx.scan), "--out", str(fx.path("ro-seg", "o"))],
             "permission denied", ("ro-seg",), prefix=_no_dac(),
             prepare=lambda: (fx.path("ro-seg", "x").parent.mkdir(exist_ok=True),
                              fx.path("ro-seg", "x").parent.chmod(0o555)),
             skip=fx.setpriv_ok and f"cannot drop root's permission bypass: {fx.setpriv_ok}"),
    ]


def misc_cases(fx: Fixtures) -> list[Case]:
    return [
        Case("unknown-command", ["generat"], "no such command", ("generat",)),
        Case("unknown-command-escape-codes", [ESC_NAME], "no such command, shown inert", ("pwned", "command")),
        Case("unknown-option", ["generate", "--out", str(fx.path("u")), "--num-scene", "1"], "no such option",
             ("--num-scene",)),
    ]


ALL_GROUPS = (generate_cases, layout_cases, show_cases, bench_cases, assets_cases, evaluate_cases, metrics_cases,
              train_cases, probe_cases, segment_cases, misc_cases)


# ------------------------------------------------------------------------------------------------
# report


def _cell(text: str, limit: int = 110) -> str:
    from assist3d.core.errors import shown

    return shown(text, limit).replace("|", "\\|")


def relative(text: str, root: Path) -> str:
    """``text`` with the temporary folder left out of its paths (``cases/x`` -> ``x``)."""
    return text.replace(str(root / "cases") + "/", "").replace(str(root) + "/", "").replace(str(root), "TMP")


def command_label(case: Case, root: Path) -> str:
    words = []
    for a in case.argv:
        a = relative(a, root)
        words.append(a if len(a) < 40 else a[:37] + "...")
    return "assist3d " + " ".join(words)


def markdown(outcomes: list[Outcome], root: Path) -> str:
    lines = ["| # | case | command | expected | outcome | class |", "| --- | --- | --- | --- | --- | --- |"]
    for i, o in enumerate(outcomes, 1):
        what = (f"exit {o.rc}: " if o.rc is not None else "") + relative(o.message or "", root)
        if o.note:
            what += f" ({o.note})"
        if o.case.owner and o.cls not in ("clear", "skipped"):
            what += f" [owner: {o.case.owner}]"
        lines.append(f"| {i} | {o.case.name} | `{_cell(command_label(o.case, root), 140).replace('`', '')}` | "
                     f"{_cell(o.case.expect, 70)} | {_cell(what, 160)} | {o.cls} |")
    return "\n".join(lines)


def summary(outcomes: list[Outcome]) -> dict[str, int]:
    counts = {c: 0 for c in (*CLASSES, "skipped")}
    for o in outcomes:
        counts[o.cls] += 1
    counts["total"] = len(outcomes)
    return counts


def summary_line(counts: dict[str, int]) -> str:
    parts = ", ".join(f"{counts[c]} {c}" for c in (*CLASSES, "skipped"))
    return f"{counts['total']} cases: {parts}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", type=Path, help="also write the results here as JSON")
    ap.add_argument("--only", help="run only cases whose name contains this")
    ap.add_argument("--keep", action="store_true", help="keep the temporary folder")
    args = ap.parse_args(argv)
    os.nice(10)  # share the machine politely
    root = Path(tempfile.mkdtemp(prefix="assist3d-fuzz-"))
    root.chmod(0o755)
    t0 = time.monotonic()
    outcomes: list[Outcome] = []
    fx: Fixtures | None = None
    try:
        fx = build_fixtures(root)
        cases = [c for group in ALL_GROUPS for c in group(fx)]
        names = [c.name for c in cases]
        assert len(names) == len(set(names)), "case names must be unique"
        for case in cases:
            if args.only and args.only not in case.name:
                continue
            o = run_case(case, fx.env, fx.cwd)
            outcomes.append(o)
            print(f"{o.cls:9s} {o.seconds:5.1f}s {case.name}: {_cell(relative(o.message, root), 140)}",
                  file=sys.stderr, flush=True)
    finally:
        if fx is not None:
            for m in reversed(fx.mounts):
                subprocess.run(["umount", "-l", str(m)], capture_output=True)
        for p in root.rglob("*"):
            if p.is_dir() and not p.is_symlink():
                try:
                    p.chmod(0o755)
                except OSError:
                    pass
        if not args.keep:
            shutil.rmtree(root, ignore_errors=True)
    counts = summary(outcomes)
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    from assist3d.core.bounds import gib, machine_memory_bytes

    memory = machine_memory_bytes()
    machine = (f"{platform.system()} {platform.release()}, {os.cpu_count()} CPUs, "
               f"{gib(memory) if memory else '? GiB'} memory, Python {platform.python_version()}, euid {os.geteuid()}")
    print(markdown(outcomes, root))
    print()
    print(f"**{summary_line(counts)}** ({stamp}; {machine}; {time.monotonic() - t0:.0f} s)")
    if args.json:
        args.json.write_text(json.dumps({
            "date": stamp, "machine": machine, "seconds": round(time.monotonic() - t0, 1), "summary": counts,
            "cases": [{"name": o.case.name, "command": command_label(o.case, root), "expected": o.case.expect,
                       "exit": o.rc, "message": relative(o.message, root), "note": o.note, "class": o.cls, "owner": o.case.owner,
                       "seconds": round(o.seconds, 2)} for o in outcomes]}, indent=1) + "\n")
    return 0 if all(o.cls in ("clear", "skipped") for o in outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
