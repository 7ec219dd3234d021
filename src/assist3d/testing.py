"""Helpers for tests and fault scripts (like ``numpy.testing``): dataset digests that leave out
wall-clock timings, and the process tree below a pid, read from Linux's ``/proc``."""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

__all__ = ["SCENE_ARRAYS", "dataset_digest", "descendants", "survivors", "wait_until_gone"]

SCENE_ARRAYS = ("coord.npy", "color.npy", "normal.npy", "instance.npy", "segment.npy")


def dataset_digest(root: str | Path) -> dict[str, str]:
    """One SHA-256 per complete-looking scene folder of ``root`` over its arrays and its layout
    (the layout's wall-clock timings left out, so two runs of the same seed compare equal)."""
    out = {}
    for d in sorted(Path(root).glob("scene_*")):
        h = hashlib.sha256()
        for name in SCENE_ARRAYS:
            h.update((d / name).read_bytes())
        lay = json.loads((d / "layout.json").read_text())
        lay.pop("seconds", None)
        lay.get("stats", {}).pop("timing", None)
        h.update(json.dumps(lay, sort_keys=True).encode())
        out[d.name] = h.hexdigest()
    return out


def _stat(pid: int) -> list[str] | None:
    """Fields of ``/proc/PID/stat`` after the command name (state first), or None if gone."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None


def descendants(root: int) -> dict[int, str]:
    """Every live process below ``root``: pid -> start time (so a reused pid is not confused)."""
    children: dict[int, list[int]] = {}
    for p in Path("/proc").iterdir():
        if p.name.isdigit() and (st := _stat(int(p.name))) is not None:
            children.setdefault(int(st[1]), []).append(int(p.name))
    found: dict[int, str] = {}
    todo = list(children.get(root, []))
    while todo:
        pid = todo.pop()
        if (st := _stat(pid)) is not None:
            found[pid] = st[19]
            todo.extend(children.get(pid, []))
    return found


def survivors(procs: dict[int, str]) -> list[int]:
    """The processes of ``procs`` (from :func:`descendants`) still running; a zombie has exited."""
    return [pid for pid, start in procs.items()
            if (st := _stat(pid)) is not None and st[19] == start and st[0] not in ("Z", "X")]


def wait_until_gone(procs: dict[int, str], timeout: float) -> list[int]:
    """:func:`survivors` after waiting up to ``timeout`` seconds for them to end."""
    deadline = time.monotonic() + timeout
    while (alive := survivors(procs)) and time.monotonic() < deadline:
        time.sleep(0.05)
    return alive
