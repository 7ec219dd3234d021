"""Interrupts end cleanly: SIGTERM / SIGINT (Ctrl-C to the whole process group) / SIGKILL on
`generate --workers 2` leave no process behind, no lock file, no temporary file, say in one line
what is complete, and a re-run completes the dataset with the bytes of an uninterrupted run."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import process as futures_process
from pathlib import Path

import pytest
import yaml

from assist3d.config import parse_config
from assist3d.export import read_scene_meta
from assist3d.core.interrupts import Interrupted, worker_pool
from assist3d.pipeline import generate_dataset, scene_name
from assist3d.testing import dataset_digest, descendants, wait_until_gone

pytestmark = [pytest.mark.skipif(not sys.platform.startswith("linux"),
                                 reason="needs Linux: /proc to find worker processes, POSIX signals"),
              pytest.mark.slow]  # signals and subprocesses: the slow tier

TINY = {
    "seed": 11,
    "assets": {"procedural_count": 60},
    "selection": {"floor_count": 6, "wall_count": 2, "on_top_count": 1},
    "room": {"area_min": 10.0, "area_max": 16.0},
    "layout": {"group_budget_s": 120.0},  # node limits, not machine load, end the layout search
    "render": {"width": 80, "height": 60, "fx": 72.2, "fy": 72.2, "vantage_points": 2, "views_per_point": 6},
}
N_SCENES = 6


# ------------------------------------------------------------------------------------ helpers


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


# a test run started in the background ignores SIGINT, and so would its children: undo that there
_PREEXEC = _default_sigint if signal.getsignal(signal.SIGINT) is signal.SIG_IGN else None


# ------------------------------------------------------------------------------------ fixtures


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> dict[str, str]:
    """The uninterrupted dataset (one process: the bytes do not depend on --workers)."""
    out = tmp_path_factory.mktemp("reference")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ASSIST3D_CACHE", str(tmp_path_factory.getbasetemp() / "assist3d-cache"))
        mp.delenv("ASSIST3D_ASSETS", raising=False)
        generate_dataset(parse_config(TINY), out, range(N_SCENES))
    digest = dataset_digest(out)
    assert len(digest) == N_SCENES
    return digest


@pytest.fixture
def command(tmp_path) -> tuple[list[str], Path]:
    cfg_file = tmp_path / "tiny.yaml"
    cfg_file.write_text(yaml.safe_dump(TINY))
    target = tmp_path / "data"
    cmd = [sys.executable, "-m", "assist3d", "-q", "generate", "--out", str(target), "--num-scenes", str(N_SCENES),
           "--config", str(cfg_file), "--workers", "2"]
    return cmd, target


def start_and_wait_for_a_scene(cmd: list[str], target: Path, *, group: bool) -> tuple[subprocess.Popen, dict]:
    """Start the run; once a worker has completed a scene, return it and its live descendants."""
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=group, preexec_fn=_PREEXEC)
    deadline = time.monotonic() + 60
    while proc.poll() is None and time.monotonic() < deadline:
        if (target / scene_name(0) / "meta.json").is_file() or (target / scene_name(1) / "meta.json").is_file():
            break
        time.sleep(0.01)
    procs = descendants(proc.pid)
    if proc.poll() is not None:
        pytest.fail(f"the run ended before it could be interrupted: {proc.returncode} {proc.stderr.read()}")
    assert len(procs) >= 3, f"expected the forkserver and 2 workers below {proc.pid}, found {procs}"
    return proc, procs


def assert_clean_folder(target: Path) -> None:
    assert not (target / ".generate.lock").exists(), "the folder lock was left behind"
    assert not list(target.rglob("*.tmp")), "temporary files were left behind"
    half = [d.name for d in target.glob("scene_*") if read_scene_meta(d, check_files=False) is None]
    assert half == [], f"half-written scene folders left behind: {half}"


def assert_rerun_completes(cmd: list[str], target: Path, reference: dict[str, str]) -> None:
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert dataset_digest(target) == reference
    assert_clean_folder(target)


# ------------------------------------------------------------------------------------ tests


@pytest.mark.parametrize("signum, to_group, code", [
    (signal.SIGTERM, False, 143),  # `kill PID`
    (signal.SIGINT, True, 130),  # Ctrl-C in a terminal: the whole foreground process group
], ids=["sigterm", "sigint-group"])
def test_a_stop_signal_ends_the_run_and_its_workers_cleanly(command, reference, signum, to_group, code):
    cmd, target = command
    proc, procs = start_and_wait_for_a_scene(cmd, target, group=to_group)
    t0 = time.monotonic()
    if to_group:
        os.killpg(proc.pid, signum)
    else:
        proc.send_signal(signum)
    _, err = proc.communicate(timeout=30)
    seconds = time.monotonic() - t0
    assert proc.returncode == code, err
    assert seconds < 10, f"took {seconds:.1f} s to stop"
    lines = [ln for ln in err.replace("\r", "\n").splitlines() if "interrupted" in ln]
    assert len(lines) == 1, err
    name = signal.Signals(signum).name
    m = re.fullmatch(rf"assist3d: interrupted by {name}: (\d+) of {N_SCENES} scenes complete in (.+); "
                     r"re-run the same command to resume", lines[0])
    assert m is not None, lines[0]
    assert "Traceback" not in err, err
    assert wait_until_gone(procs, 5.0) == [], "processes of the run outlived it"
    complete = sum(read_scene_meta(d) is not None for d in target.glob("scene_*"))
    assert int(m.group(1)) == complete and 1 <= complete < N_SCENES
    assert_clean_folder(target)
    before = {p: p.stat().st_mtime_ns for p in target.rglob("*")}
    time.sleep(0.5)
    assert {p: p.stat().st_mtime_ns for p in target.rglob("*")} == before, "something still writes into --out"
    assert_rerun_completes(cmd, target, reference)


def test_workers_exit_by_themselves_when_the_parent_is_killed(command, reference):
    cmd, target = command
    proc, procs = start_and_wait_for_a_scene(cmd, target, group=False)
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=30)
    assert wait_until_gone(procs, 5.0) == [], "workers outlived a killed parent"
    # a SIGKILL leaves what it leaves (lock file, temporary files); the re-run cleans up and completes
    assert_rerun_completes(cmd, target, reference)


def _sleep(seconds: float) -> float:
    time.sleep(seconds)
    return seconds


def test_the_worker_pool_stops_its_workers_on_an_interrupt():
    before = descendants(os.getpid())  # e.g. a forkserver an earlier test started: it stays
    t0 = time.monotonic()
    with pytest.raises(Interrupted):
        with worker_pool(2) as pool:
            for _ in range(4):
                pool.submit(_sleep, 60.0)
            procs = {pid: start for pid, start in descendants(os.getpid()).items() if before.get(pid) != start}
            raise Interrupted(signal.SIGTERM)
    # the executor's manager thread has ended by then: had it still been closing its wake-up pipe
    # when the interpreter's exit hook wrote to it, a stopped run printed an OSError traceback
    managers = [t for t in threading.enumerate() if isinstance(t, futures_process._ExecutorManagerThread)]
    assert managers == []
    assert len(procs) >= 2
    assert wait_until_gone(procs, 5.0) == []
    assert time.monotonic() - t0 < 10


def test_the_lock_file_goes_with_the_run_and_a_second_writer_is_refused(tmp_path):
    from assist3d.core.errors import DataError
    from assist3d.pipeline.dataset import _folder_lock

    with _folder_lock(tmp_path):
        assert (tmp_path / ".generate.lock").is_file()
        with pytest.raises(DataError, match="another `assist3d generate`"):
            with _folder_lock(tmp_path):
                pass
    assert not (tmp_path / ".generate.lock").exists()
    with _folder_lock(tmp_path):  # free again
        pass


def test_an_interrupt_message_says_what_is_complete_and_its_exit_code():
    e = Interrupted(signal.SIGINT, "3 of 8 scenes complete in d; re-run the same command to resume")
    assert e.exit_code == 130 and Interrupted(signal.SIGTERM).exit_code == 143
    assert str(e) == "interrupted by SIGINT: 3 of 8 scenes complete in d; re-run the same command to resume"
    assert not isinstance(e, Exception)  # `except Exception` blocks let it through
