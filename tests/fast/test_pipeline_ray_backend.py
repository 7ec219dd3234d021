"""generate --backend ray on a real local Ray cluster (a head and a second node on loopback, 1 CPU
each): byte-identical to --workers 1, survives a killed worker and a killed driver; skipped when
Ray is not installed."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
import yaml

from assist3d.config import parse_config
from assist3d.core.errors import ConfigError
from assist3d.export import read_scene_meta
from assist3d.pipeline import generate_dataset, scene_name
from assist3d.testing import dataset_digest
from test_pipeline_generate import TINY

pytestmark = pytest.mark.slow  # signals and subprocesses: the slow tier


ray = pytest.importorskip("ray")

SCENES = 4


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _ray(*args: str, env: dict) -> None:
    exe = Path(sys.executable).parent / "ray"
    subprocess.run([str(exe), *args], check=True, env=env, timeout=180, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def cache_env(tmp_path_factory):
    cache = str(tmp_path_factory.getbasetemp() / "assist3d-cache")
    # RAY_AUTH_MODE: a token left in ~/.ray by an earlier local ray.init() turns token auth on for a
    # new head but not for a node joining it; this test cluster lives on loopback only
    env = {**os.environ, "ASSIST3D_CACHE": cache, "RAY_USAGE_STATS_ENABLED": "0", "RAY_AUTH_MODE": "disabled"}
    env.pop("ASSIST3D_ASSETS", None)
    env.pop("RAY_ADDRESS", None)
    return env


@pytest.fixture(scope="module")
def cluster(cache_env):
    """A Ray head and a second node on 127.0.0.1, 1 CPU each; yields the head's address."""
    port = _free_port()
    temp = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths live under it
    common = ["--num-cpus=1", "--node-ip-address=127.0.0.1", "--disable-usage-stats"]
    _ray("start", "--head", f"--port={port}", "--include-dashboard=false", f"--temp-dir={temp}", *common,
         env=cache_env)
    try:
        _ray("start", f"--address=127.0.0.1:{port}", *common, env=cache_env)
        yield f"127.0.0.1:{port}"
    finally:
        _ray("stop", "--force", env=cache_env)


@pytest.fixture(scope="module")
def reference(tmp_path_factory, cache_env):
    out = tmp_path_factory.mktemp("ref")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ASSIST3D_CACHE", cache_env["ASSIST3D_CACHE"])
        mp.delenv("ASSIST3D_ASSETS", raising=False)
        generate_dataset(parse_config(TINY), out, range(SCENES))
    return dataset_digest(out)


def _ray_run(out: Path, address: str, cache_env: dict, **kw):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ASSIST3D_CACHE", cache_env["ASSIST3D_CACHE"])
        mp.setenv("RAY_AUTH_MODE", "disabled")
        mp.delenv("ASSIST3D_ASSETS", raising=False)
        return generate_dataset(parse_config(TINY), out, range(SCENES), backend="ray", ray_address=address, **kw)


def test_ray_run_is_byte_identical_to_one_worker(cluster, reference, cache_env, tmp_path):
    run = _ray_run(tmp_path / "ray", cluster, cache_env)
    assert len(run.generated) == SCENES and run.errors == []
    assert dataset_digest(tmp_path / "ray") == reference
    c = run.cluster
    assert c["nodes"] == 2 and c["cpus"] == 2 and c["scenes"] == SCENES and c["scenes_per_minute"] > 0
    assert sum(v["scenes"] for v in c["per_node"].values()) == SCENES
    assert not list((tmp_path / "ray").glob(".ray-*"))  # the storage probe cleaned up


def _ray_workers() -> list[int]:
    pids = []
    for p in Path("/proc").iterdir():
        if p.name.isdigit():
            try:
                cmd = (p / "cmdline").read_bytes()
            except OSError:
                continue
            if cmd.startswith(b"ray::") and b"scene_in_ray_worker" in cmd:
                pids.append(int(p.name))
    return pids


def test_a_killed_worker_loses_only_time(cluster, reference, cache_env, tmp_path):
    killed: list[int] = []

    def on_scene(meta, skipped):
        if not killed:
            for _ in range(100):  # the next scene's task is running somewhere: kill its process
                pids = _ray_workers()
                if pids:
                    os.kill(pids[0], signal.SIGKILL)
                    killed.append(pids[0])
                    return
                time.sleep(0.05)

    run = _ray_run(tmp_path / "ray", cluster, cache_env, on_scene=on_scene)
    assert killed, "no running scene task was found to kill"
    assert run.errors == [] and dataset_digest(tmp_path / "ray") == reference


def test_a_killed_driver_resumes_from_complete_scenes(cluster, reference, cache_env, tmp_path):
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(yaml.safe_dump(TINY))
    out = tmp_path / "ray"
    cmd = [sys.executable, "-m", "assist3d", "generate", "--out", str(out), "--num-scenes", str(SCENES),
           "--config", str(cfg), "--backend", "ray", "--ray-address", cluster, "--json"]
    driver = subprocess.Popen(cmd, env=cache_env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and driver.poll() is None:
        if any(read_scene_meta(out / scene_name(i), check_files=False) for i in range(SCENES)):
            break
        time.sleep(0.2)
    complete_before = sum(read_scene_meta(out / scene_name(i), check_files=False) is not None for i in range(SCENES))
    driver.kill()
    driver.wait()
    assert complete_before >= 1
    again = subprocess.run(cmd, env=cache_env, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr[-2000:]
    assert dataset_digest(out) == reference


def test_unreachable_address_fails_fast_and_writes_nothing(tmp_path, cache_env):
    port = _free_port()  # nothing listens there
    out = tmp_path / "never"
    t0 = time.monotonic()
    with pytest.raises(ConfigError, match=f"cannot reach 127.0.0.1:{port}"):
        _ray_run(out, f"127.0.0.1:{port}", cache_env)
    assert time.monotonic() - t0 < 30
    assert not out.exists()
