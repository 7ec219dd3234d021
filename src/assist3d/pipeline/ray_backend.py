"""Scene generation on a Ray cluster (``assist3d generate --backend ray``; optional extra ``[ray]``).

The dataset loop of :mod:`assist3d.pipeline` hands its scene jobs to :func:`run_scenes`, which runs
each as one Ray task and gives every result back to the loop in the driver, so the driver alone
writes the manifest, exactly as with local worker processes. What this module adds:

* **Connection** (:func:`connect`): ``address=None`` lets Ray find a running cluster (``RAY_ADDRESS``
  or the latest ``ray start`` on this machine) and otherwise start a local one; an explicit
  ``host:port`` (or ``ray://host:port``) is first checked with a plain TCP connection, so an
  unreachable address fails within :data:`CONNECT_TIMEOUT_S` with a clear message, before anything
  is written.
* **Shared storage check** (:func:`check_shared_storage`): one task per alive node must see a file
  the driver wrote into the output folder and be able to write there; otherwise the run stops at
  once naming the node. Workers write their scene folders straight into the output folder.
* **Fault tolerance**: a task whose worker process or node dies is retried by Ray
  (``max_retries``); scene errors (:class:`~assist3d.core.errors.AssistError`) are not retried and are
  reported like local ones (a re-run retries them). Killing the driver leaves complete scenes
  (their completion markers) and the re-run resumes from them.
* **Back-pressure**: at most ``max_in_flight`` tasks are submitted at a time (default twice the
  cluster's CPUs), so the driver's memory does not grow with the number of scenes.
* **Accounting**: scenes per node and the cluster's throughput (:class:`ClusterStats`).

Ray is imported only inside these functions: the core install does not need it.
"""

from __future__ import annotations

import logging
import os
import socket
import time
import uuid
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

from ..core.errors import ConfigError, DataError, FaultError

log = logging.getLogger(__name__)

CONNECT_TIMEOUT_S = 30.0
DEFAULT_GCS_PORT = 6379
DEFAULT_CLIENT_PORT = 10001
MAX_RETRIES = 3
MAX_IN_FLIGHT_CAP = 4096


@dataclass
class ClusterStats:
    """What the cluster did: scenes per node, wall seconds, throughput."""

    address: str
    nodes: int
    cpus: float
    seconds: float = 0.0
    per_node: Counter = field(default_factory=Counter)

    def as_dict(self) -> dict[str, Any]:
        done = sum(self.per_node.values())
        minutes = self.seconds / 60 if self.seconds > 0 else 0.0
        return {"backend": "ray", "address": self.address, "nodes": self.nodes, "cpus": self.cpus,
                "scenes": done, "seconds": round(self.seconds, 2),
                "scenes_per_minute": round(done / minutes, 2) if minutes else None,
                "per_node": {n: {"scenes": c, "scenes_per_minute": round(c / minutes, 2) if minutes else None}
                             for n, c in sorted(self.per_node.items())}}


def _host_port(address: str) -> tuple[str, int]:
    rest = address
    client = rest.startswith("ray://")
    if client:
        rest = rest[len("ray://"):]
    host, sep, port = rest.rpartition(":")
    if not sep:
        return rest, DEFAULT_CLIENT_PORT if client else DEFAULT_GCS_PORT
    try:
        return host.strip("[]"), int(port)
    except ValueError:
        raise ConfigError(f"--ray-address {address!r}: expected HOST:PORT or ray://HOST:PORT") from None


def check_address(address: str | None, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
    """Raise :class:`ConfigError` when an explicit ``address`` cannot be reached over TCP."""
    if address is None or address in ("auto", "local"):
        return
    host, port = _host_port(address)
    try:
        with socket.create_connection((host, port), timeout=min(timeout_s, 10.0)):
            pass
    except OSError as e:
        raise ConfigError(f"--ray-address {address}: cannot reach {host}:{port} ({e.strerror or e}); is a Ray head "
                          f"running there (`ray start --head --port {port}`)?") from None


def connect(address: str | None) -> None:
    """Connect this process to Ray (starting a local instance when there is no cluster)."""
    try:
        import ray
    except ImportError:
        raise ConfigError("--backend ray needs Ray: pip install 'assist3d[ray]'") from None
    check_address(address)
    if ray.is_initialized():
        return
    t0 = time.monotonic()
    try:
        # the workers see this process's ASSIST3D_* settings (catalog and cache folders)
        env = {k: v for k, v in os.environ.items() if k.startswith("ASSIST3D_")}
        ray.init(address=None if address in (None, "local") else address, include_dashboard=False,
                 log_to_driver=False, configure_logging=False, runtime_env={"env_vars": env} if env else None)
    except (ConnectionError, RuntimeError, ValueError) as e:
        raise ConfigError(f"--ray-address {address or 'auto'}: cannot connect to Ray ({e})") from None
    log.info("ray: connected in %.1f s (%s)", time.monotonic() - t0,
             address or os.environ.get("RAY_ADDRESS") or "auto: a running local cluster or a new instance")


def disconnect() -> None:
    """Leave the cluster (a local instance started by :func:`connect` stops with it)."""
    import ray

    if ray.is_initialized():
        ray.shutdown()


def _probe_node(out: str, token: str) -> dict:
    """Runs on one node: does it see the driver's token file in ``out`` and can it write there?"""
    path = Path(out) / f".ray-probe-{token}"
    try:
        visible = path.read_text() == token
    except OSError:
        visible = False
    writable, error = True, ""
    test = Path(out) / f".ray-write-{token}-{socket.gethostname()}-{os.getpid()}"
    try:
        test.write_text("ok")
        test.unlink()
    except OSError as e:
        writable, error = False, str(e)
    return {"host": socket.gethostname(), "visible": visible, "writable": writable, "error": error}


def check_shared_storage(out: Path) -> int:
    """Every alive node must see ``out`` (a file written here) and write into it; returns the node count."""
    import ray
    from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

    nodes = [n for n in ray.nodes() if n.get("Alive")]
    token = uuid.uuid4().hex
    marker = out / f".ray-probe-{token}"
    marker.write_text(token)
    try:
        probe = ray.remote(num_cpus=0, max_retries=0)(_probe_node)
        refs = {n["NodeManagerAddress"]: probe.options(scheduling_strategy=NodeAffinitySchedulingStrategy(
            n["NodeID"], soft=False)).remote(str(out), token) for n in nodes}
        for ip, ref in refs.items():
            r = ray.get(ref, timeout=120)
            if not r["visible"]:
                raise DataError(f"{out}: Ray node {ip} ({r['host']}) does not see this folder; --backend ray "
                                f"needs an output folder on storage every node mounts at the same path "
                                f"(NFS, Lustre, a cloud file system)")
            if not r["writable"]:
                raise DataError(f"{out}: Ray node {ip} ({r['host']}) cannot write here ({r['error']})")
    finally:
        marker.unlink(missing_ok=True)
    return len(nodes)


def run_scenes(task: Callable[..., tuple[dict, str]], args: tuple, jobs: Sequence[Any],
               done: Callable[[dict], None], fail: Callable[[int, BaseException], None], *, out: Path,
               address: str | None, max_in_flight: int | None = None) -> ClusterStats:
    """Run ``task(*args, job) -> (scene meta, host)`` for every job as one Ray task; ``done`` gets
    each meta in the driver, ``fail(job.index, error)`` each scene that could not be made."""
    import ray

    resources = ray.cluster_resources()
    cpus = float(resources.get("CPU", 1.0))
    nodes = check_shared_storage(out)
    stats = ClusterStats(address=address or os.environ.get("RAY_ADDRESS") or "auto", nodes=nodes, cpus=cpus)
    limit = max_in_flight or int(min(MAX_IN_FLIGHT_CAP, max(2, 2 * cpus)))
    remote = ray.remote(num_cpus=1, max_retries=MAX_RETRIES, retry_exceptions=False)(task)
    log.info("ray: %d scenes on %d node(s), %g CPUs, at most %d in flight", len(jobs), nodes, cpus, limit)
    t0 = time.monotonic()
    queue = list(jobs)
    pending: dict[Any, Any] = {}
    try:
        while queue or pending:
            while queue and len(pending) < limit:
                job = queue.pop(0)
                pending[remote.remote(*args, job)] = job
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                job = pending.pop(ref)
                try:
                    meta, host = ray.get(ref)
                except ray.exceptions.RayTaskError as e:
                    cause = getattr(e, "cause", None)
                    fail(job.index, cause if isinstance(cause, BaseException) else e)
                    continue
                except (ray.exceptions.WorkerCrashedError, ray.exceptions.NodeDiedError,
                        ray.exceptions.TaskCancelledError, ray.exceptions.ObjectLostError) as e:
                    fail(job.index, FaultError(f"scene {job.index}: its Ray worker died {MAX_RETRIES + 1} times "
                                               f"({type(e).__name__})"))
                    continue
                stats.per_node[host] += 1
                done(meta)
    except BaseException:
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    finally:
        stats.seconds = time.monotonic() - t0
    return stats
