"""Training scenes on disk instead of in memory: a *scene pack*.

A training step reads two scenes of the training set, so the set need not live in memory. A pack
holds the arrays a :class:`.data.Scene` needs (coordinates, colours, instance ids) of every scene
back to back in three flat files, written once when the training set is read; a scene is then a
slice of three memory maps. Memory is bounded by what the operating system caches, not by the
number of scenes: 2,000 generated scenes (about 12 GB as arrays) train like 60.

Each scene is read and checked through its dataset reader exactly as for an in-memory set, and the
pack returns the very same arrays (same dtypes and values), so a run on a pack and a run on a list
give bit-identical training. A pack pickles as its folder name and re-opens its maps in the process
that unpickles it (data loader workers), so no array is copied to a worker.

Layout of a pack folder::

    coord.f32      (N, 3) float32, all scenes' points in order
    color.u8       (N, 3) uint8
    instance.i32   (N,)   int32
    info.json      what the writer recorded about the scenes (optional; e.g. the probe's training sets)
    offsets.npy    (S + 1,) int64, scene k is rows offsets[k]:offsets[k + 1]; written last

:func:`temporary_pack` puts a pack in a hidden folder of an output directory (never in ``/tmp``,
which may be memory) for the length of a run, and removes the packs that killed runs on this host
left behind.
"""

from __future__ import annotations

import logging
import os
import shutil
import socket
import tempfile
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ...core import reading
from ...core.errors import DataError
from ...core.fileio import write_json_atomic
from .data import Scene

log = logging.getLogger(__name__)

__all__ = ["ScenePack", "temporary_pack", "PACK_PREFIX"]

#: the name of a temporary pack folder starts with this, then ``HOST-PID-``
PACK_PREFIX = ".train-pack-"

_FILES = (("coord.f32", np.float32, 3), ("color.u8", np.uint8, 3), ("instance.i32", np.int32, 0))


class ScenePack(Sequence[Scene]):
    """The scenes of a pack folder (see the module docs), read through memory maps; use
    :meth:`write` to make one."""

    def __init__(self, root: str | os.PathLike) -> None:
        self.root = Path(root)
        path = self.root / "offsets.npy"
        if not path.is_file():
            raise DataError(f"{path}: missing; {self.root} is not a finished scene pack")
        self.offsets = reading.read_npy(path)
        if self.offsets.dtype != np.int64 or self.offsets.ndim != 1 or len(self.offsets) < 1 or np.any(np.diff(self.offsets) < 0):
            raise DataError(f"{path}: offsets must be a non-decreasing 1-d int64 array")
        self._maps: tuple[np.ndarray, ...] | None = None

    @classmethod
    def write(cls, root: str | os.PathLike, scenes: Iterable[Scene], info: Callable[[], dict] | None = None
              ) -> "ScenePack":
        """Write ``scenes`` (read one at a time, never held together) as a pack in ``root``; ``info``, called
        once they are written, gives what :attr:`info` returns."""
        out = Path(root)
        out.mkdir(parents=True, exist_ok=True)
        offsets = [0]
        handles = [open(out / name, "wb") for name, _, _ in _FILES]
        try:
            for s in scenes:
                n = len(s.coord)
                parts = (s.coord, s.color, s.instance)
                for h, (name, dtype, width), a in zip(handles, _FILES, parts):
                    shape = (n, width) if width else (n,)
                    if a.shape != shape:
                        raise DataError(f"scene pack {out}: {name} of a scene has shape {a.shape}, expected {shape}")
                    h.write(np.ascontiguousarray(a, dtype).tobytes())
                offsets.append(offsets[-1] + n)
        finally:
            for h in handles:
                h.close()
        if info is not None:
            write_json_atomic(out / "info.json", info())
        np.save(out / "offsets.npy", np.asarray(offsets, np.int64))  # last: marks the pack finished
        return cls(out)

    @property
    def info(self) -> dict:
        """What the writer recorded (``{}`` when nothing)."""
        path = self.root / "info.json"
        got = reading.read_json(path) if path.is_file() else {}
        if not isinstance(got, dict):
            raise DataError(f"{path}: expected a JSON object")
        return got

    def _open(self) -> tuple[np.ndarray, ...]:
        if self._maps is None:
            total = int(self.offsets[-1])
            maps = []
            for name, dtype, width in _FILES:
                shape = (total, width) if width else (total,)
                if total == 0:
                    maps.append(np.zeros(shape, dtype))
                    continue
                path = self.root / name
                if path.stat().st_size != total * np.dtype(dtype).itemsize * max(width, 1):
                    raise DataError(f"{path}: size does not match offsets.npy; the pack is damaged")
                maps.append(np.memmap(path, dtype=dtype, mode="r", shape=shape).view(np.ndarray))
            self._maps = tuple(maps)
        return self._maps

    def __len__(self) -> int:
        return len(self.offsets) - 1

    def __getitem__(self, i):  # type: ignore[override]
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        k = int(i)
        if k < 0:
            k += len(self)
        if not 0 <= k < len(self):
            raise IndexError(f"scene {i} of a pack of {len(self)}")
        a, b = int(self.offsets[k]), int(self.offsets[k + 1])
        coord, color, instance = self._open()
        return Scene(coord=coord[a:b], color=color[a:b], instance=instance[a:b])

    def __iter__(self) -> Iterator[Scene]:
        return (self[k] for k in range(len(self)))

    @property
    def points(self) -> np.ndarray:
        """(S,) int64 points per scene."""
        return np.diff(self.offsets)

    def __getstate__(self) -> dict:
        return {"root": str(self.root), "offsets": self.offsets}

    def __setstate__(self, state: dict) -> None:
        self.root, self.offsets, self._maps = Path(state["root"]), state["offsets"], None

    def __repr__(self) -> str:
        return f"ScenePack({str(self.root)!r}, scenes={len(self)}, points={int(self.offsets[-1])})"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        return True
    return True


def _remove_stale(parent: Path, host: str) -> None:
    """Remove the packs in ``parent`` that processes of this host, no longer running, left behind."""
    for d in parent.glob(f"{PACK_PREFIX}{host}-*"):
        try:
            pid = int(d.name[len(PACK_PREFIX) + len(host) + 1:].split("-", 1)[0])
        except ValueError:
            continue
        if d.is_dir() and pid != os.getpid() and not _alive(pid):
            log.info("removing %s, left by a stopped run", d)
            shutil.rmtree(d, ignore_errors=True)


@contextmanager
def temporary_pack(parent: str | os.PathLike) -> Iterator[Path]:
    """A new empty folder for a pack inside ``parent`` (``.train-pack-HOST-PID-`` and a random suffix),
    removed on exit; packs that stopped runs of this host left in ``parent`` are removed first."""
    base = Path(parent)
    base.mkdir(parents=True, exist_ok=True)
    host = socket.gethostname().replace("-", "_") or "host"
    _remove_stale(base, host)
    path = Path(tempfile.mkdtemp(prefix=f"{PACK_PREFIX}{host}-{os.getpid()}-", dir=base))
    try:
        yield path
    finally:
        shutil.rmtree(path, ignore_errors=True)
