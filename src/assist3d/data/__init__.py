"""Dataset readers: every benchmark format becomes a :class:`SceneDataset` of ``PointSample``.

Open one with a spec ``FORMAT:PATH`` plus optional reader options as a URL-style query,
``FORMAT:PATH?key=value&key=value``:

==========  =============================================================  ====================
format      PATH                                                           options
==========  =============================================================  ====================
scannet     folder of ScanNet v2 scene folders (or ``scans/``'s parent)     ``labels=TSV``, ``objects``
scannetpp   ScanNet++ root (holding ``data/``) or ``data/``                 -
s3dis       ``Stanford3dDataset_v1.2_Aligned_Version``, an area or a room   ``cache=1``
pointcept   Pointcept scene folder, split folder or root of splits         ``segment``, ``ignore``
assist3d    our generator's output folder                                  -
array       one ``(N, 8)`` ``.npy`` or a folder of them                    ``objects``
scan        one ``.ply`` / ``(N, 3|6|8)`` ``.npy`` scan or a folder of them -
==========  =============================================================  ====================

In every reader, objects are the points with ``instance >= 0``; ``instance == -1`` is void. The
ScanNet-protocol readers count the 18 benchmark classes as objects; ``?objects=annotated`` counts every
annotated instance but walls, floors (and ceilings) instead (Pointcept: ``?ignore=0,1`` with
``segment20``). Bad
points and labels are refused with a :class:`~assist3d.core.errors.DataError` naming the file; bad
colours and normals are cleaned with a warning (``docs/evaluation.md``, "Input validation").
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable
from urllib.parse import parse_qsl

from ..core.errors import ConfigError
from ..core.registry import Registry
from .array import ArrayDataset
from .base import SceneDataset
from .pointcept import PointceptDataset
from .s3dis import S3DISDataset
from .scannet import ScanNetDataset
from .scannetpp import ScanNetPPDataset
from .scanfile import ScanDataset

__all__ = ["FORMATS", "READERS", "Reader", "SceneDataset", "open_dataset", "parse_spec"]



@dataclass(frozen=True)
class Reader:
    """A dataset format: ``open(path, **options)`` and the ``?key=value`` options it accepts."""

    open: Callable[..., SceneDataset]
    options: frozenset[str] = frozenset()


#: dataset formats by name (the ``FORMAT`` of ``FORMAT:PATH``)
READERS: Registry[Reader] = Registry("dataset format")
READERS.add("scannet", Reader(lambda p, **kw: ScanNetDataset(p, **kw), frozenset({"labels", "objects"})))
READERS.add("scannetpp", Reader(lambda p, **kw: ScanNetPPDataset(p, **kw)))
READERS.add("s3dis", Reader(lambda p, **kw: S3DISDataset(p, **kw), frozenset({"cache"})))
READERS.add("pointcept", Reader(lambda p, **kw: PointceptDataset(p, fmt="pointcept", **kw), frozenset({"segment", "ignore"})))
READERS.add("assist3d", Reader(lambda p, **kw: PointceptDataset(p, fmt="assist3d", **kw)))
READERS.add("array", Reader(lambda p, **kw: ArrayDataset(p, **kw), frozenset({"objects"})))
READERS.add("scan", Reader(lambda p, **kw: ScanDataset(p, **kw)))
FORMATS: tuple[str, ...] = READERS.names()  # the built-in formats


def parse_spec(spec: str) -> tuple[str, Path, dict[str, str]]:
    """Split ``FORMAT:PATH[?key=value&...]`` into (format, path, options); validate the format."""
    if ":" not in spec:
        raise ConfigError(f"dataset {spec!r}: expected FORMAT:PATH with FORMAT one of {', '.join(READERS.names())}")
    fmt, rest = spec.split(":", 1)
    fmt = fmt.strip().lower()
    if fmt not in READERS:
        raise ConfigError(f"dataset {spec!r}: unknown format {fmt!r}{READERS.hint(fmt)}")
    path, _, query = rest.partition("?")
    if not path:
        raise ConfigError(f"dataset {spec!r}: empty PATH")
    options = dict(parse_qsl(query, keep_blank_values=True, strict_parsing=False)) if query else {}
    allowed = READERS.get(fmt).options
    unknown = sorted(set(options) - allowed)
    if unknown:
        raise ConfigError(
            f"dataset {spec!r}: unknown option(s) {unknown} for format {fmt!r}"
            + (f"; allowed: {', '.join(sorted(allowed))}" if allowed else "; it takes none")
        )
    return fmt, Path(path).expanduser(), options


def open_dataset(spec: str) -> SceneDataset:
    """Open a dataset from ``FORMAT:PATH[?options]`` (see the module docstring).

    Raises :class:`ConfigError` for a bad spec and :class:`DataError` for a missing or empty
    dataset. Scenes load lazily, one :class:`PointSample` per ``dataset[i]`` or ``load(id)``.
    """
    fmt, path, options = parse_spec(spec)
    return READERS.get(fmt).open(path, **options)
