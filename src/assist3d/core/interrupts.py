"""Clean ends on SIGINT / SIGTERM / SIGHUP, and worker processes that never outlive their parent.

The command line turns these signals into :class:`Interrupted` (raised in the main thread), so
``finally`` blocks and context managers run: atomic writes drop their temporary files, process
pools stop their workers (:func:`worker_pool`), folder locks are released. Signals that arrive
while that cleanup runs are ignored, so a second Ctrl-C cannot cut it short. The command then
prints one line and exits with ``128 + signal number`` (130 for SIGINT, 143 for SIGTERM).

Workers started by :func:`worker_pool` ignore SIGINT (the parent stops them), die by SIGTERM's
default action, and exit on their own when the parent process disappears, even by SIGKILL:
``prctl(PR_SET_PDEATHSIG)`` on Linux for the process that forked them, and a watchdog thread that
polls the parent pid everywhere (multiprocessing's forkserver, not the parent, forks them).
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from typing import Any, Callable, Iterator

__all__ = ["Interrupted", "exit_on_signals", "worker_pool", "stop_pool", "set_parent_death_signal",
           "process_alive", "process_identity"]

STOP_SIGNALS: tuple[int, ...] = tuple(
    s for s in (getattr(signal, n, None) for n in ("SIGINT", "SIGTERM", "SIGHUP")) if s is not None)
WATCH_INTERVAL_S = 0.25  # how often a worker checks that its parent is still there
STOP_TIMEOUT_S = 3.0  # how long stopped workers get to die of SIGTERM before SIGKILL
_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>

_received: int | None = None  # the first stop signal of this run, once it arrived


class Interrupted(BaseException):
    """A stop signal arrived. ``detail`` says what is complete and how to go on.

    A BaseException like KeyboardInterrupt: ``except Exception`` blocks let it through."""

    def __init__(self, signum: int, detail: str = "") -> None:
        super().__init__(signum, detail)
        self.signum = int(signum)
        self.detail = detail

    @property
    def exit_code(self) -> int:
        """The shell convention: 128 + the signal number (130 SIGINT, 143 SIGTERM)."""
        return 128 + self.signum

    @property
    def signal_name(self) -> str:
        try:
            return signal.Signals(self.signum).name
        except ValueError:
            return f"signal {self.signum}"

    def __str__(self) -> str:
        return f"interrupted by {self.signal_name}: {self.detail or 're-run the same command to finish'}"


def _on_signal(signum: int, frame: Any) -> None:
    global _received
    if _received is not None:  # already stopping: let the cleanup finish
        return
    _received = signum
    raise Interrupted(signum)


@contextmanager
def exit_on_signals(signals: tuple[int, ...] = STOP_SIGNALS) -> Iterator[None]:
    """Raise :class:`Interrupted` in the main thread on ``signals`` while the block runs.

    Signals already ignored (``nohup``, background jobs) stay ignored; outside the main thread
    this does nothing (Python delivers signals to the main thread only)."""
    global _received
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in signals}
    _received = None
    for s, handler in previous.items():
        if handler is not signal.SIG_IGN:
            signal.signal(s, _on_signal)
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler if handler is not None else signal.SIG_DFL)
        _received = None


# ------------------------------------------------------------------------------------------
# the parent of a worker, seen from the worker
# ------------------------------------------------------------------------------------------


def process_identity(pid: int) -> str | None:
    """``"pid:start time"`` from /proc (Linux), so a reused pid is not taken for the same
    process; None where /proc is missing or the process is gone."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            fields = f.read().rsplit(b")", 1)[1].split()
    except (OSError, IndexError):
        return None
    if len(fields) < 20 or fields[0] in (b"Z", b"X"):  # a zombie has exited already
        return None
    return f"{pid}:{fields[19].decode()}"


def process_alive(pid: int, identity: str | None) -> bool:
    """Whether process ``pid`` (as identified by :func:`process_identity`) is still running."""
    if identity is not None:
        return process_identity(pid) == identity
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def set_parent_death_signal(signum: int = signal.SIGKILL) -> bool:
    """Linux: deliver ``signum`` to this process when the thread that forked it exits.
    Elsewhere (or if the call fails) nothing happens and False is returned."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(signum), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch_parent(pid: int, identity: str | None, interval: float) -> None:
    while process_alive(pid, identity):
        time.sleep(interval)
    os._exit(1)  # orphaned: the parent is gone, nobody wants this work any more


def _init_worker(parent: int, identity: str | None, initializer: Callable[..., None] | None,
                 initargs: tuple) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole group: the parent decides
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a forked worker inherits the parent's handler
    set_parent_death_signal()
    if not process_alive(parent, identity):
        os._exit(1)
    threading.Thread(target=_watch_parent, args=(parent, identity, WATCH_INTERVAL_S), daemon=True,
                     name="assist3d-parent-watch").start()
    if initializer is not None:
        initializer(*initargs)


# ------------------------------------------------------------------------------------------
# the pool, seen from the parent
# ------------------------------------------------------------------------------------------


def stop_pool(pool: ProcessPoolExecutor, timeout: float = STOP_TIMEOUT_S) -> None:
    """Cancel what has not started and end the workers now: SIGTERM, then SIGKILL after ``timeout``."""
    # the executor keeps no public list of its workers before Python 3.14 (terminate_workers)
    processes = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)  # shutdown() forgets it
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        if p.is_alive():
            p.terminate()
    deadline = time.monotonic() + timeout
    for p in processes:
        p.join(max(0.0, deadline - time.monotonic()))
    for p in processes:
        if p.is_alive():
            p.kill()
            p.join(1.0)
    # Wait for the executor's manager thread too: it closes its wake-up pipe as it ends, and if that
    # happens while the interpreter's exit hook writes to the same pipe (Python 3.11 checks, then
    # writes, without a lock), the exit prints an OSError traceback after our one-line message.
    if manager is not None and manager.is_alive():
        manager.join(timeout)


@contextmanager
def worker_pool(max_workers: int, *, mp_context: Any = None, initializer: Callable[..., None] | None = None,
                initargs: tuple = ()) -> Iterator[ProcessPoolExecutor]:
    """A ProcessPoolExecutor whose workers never outlive the block's process.

    On normal exit it waits for the workers as usual; on any exception (an error in a job, an
    :class:`Interrupted`) it cancels pending jobs and stops the workers at once, then re-raises.
    ``initializer`` must be picklable (a module-level function), as for ProcessPoolExecutor."""
    parent = os.getpid()
    pool = ProcessPoolExecutor(max_workers=max_workers, mp_context=mp_context, initializer=_init_worker,
                               initargs=(parent, process_identity(parent), initializer, tuple(initargs)))
    try:
        yield pool
        pool.shutdown(wait=True)
    except BaseException:
        stop_pool(pool)
        raise
