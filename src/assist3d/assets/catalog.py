"""An asset catalog: a folder with ``index.json`` and a cache of normalised meshes.

Layout of a catalog folder::

    index.json            {"format": "assist3d-catalog", "version": 1,
                           "assets": [AssetRecord.to_json(), ...],
                           "skipped": [{"path", "reason", "source"}, ...]}
    meshes/<hash>.npz     vertices (V,3) float32, faces (F,3) int32, face_colors (F,3) uint8

Meshes are written first (atomically), the index last (atomically), so an interrupted import
leaves the previous index intact and never lists a half-written mesh. Re-importing the same
asset id replaces its record (idempotent).
"""

from __future__ import annotations

import logging
import threading
from collections import Counter, OrderedDict
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from ..core.contracts import GROUPS, AssetRecord, MeshData, SkippedAsset
from ..core import reading
from ..core.errors import AssetError, shown
from ..core.fileio import write_json_atomic, write_npz_atomic
from ..core.paths import inside
from ..core.rng import stable_hash

log = logging.getLogger(__name__)

INDEX_NAME = "index.json"
FORMAT = "assist3d-catalog"
VERSION = 1


def mesh_file_name(asset_id: str) -> str:
    """Cache path (relative to the catalog) of an asset's mesh: a hash of its id."""
    return f"meshes/{stable_hash(asset_id, 24)}.npz"


def save_mesh(path: str | Path, mesh: MeshData) -> None:
    write_npz_atomic(path, vertices=mesh.vertices, faces=mesh.faces, face_colors=mesh.face_colors)


def load_mesh_file(path: str | Path) -> MeshData:
    path = Path(path)
    if not path.exists():
        raise AssetError(f"{shown(path, 400)}: cached mesh missing; re-run the import")
    try:
        z = reading.read_npz(path, keys=("vertices", "faces", "face_colors"), error=AssetError, what="cached mesh")
        return MeshData(
            vertices=np.array(z["vertices"], dtype=np.float32),
            faces=np.array(z["faces"], dtype=np.int32),
            face_colors=np.array(z["face_colors"], dtype=np.uint8),
        )
    except AssetError as e:
        raise AssetError(f"{shown(path, 400)}: cached mesh unreadable ({reading.problem(e, path)}); "
                         "re-run the import") from None
    except (TypeError, ValueError, OverflowError) as e:
        raise AssetError(f"{shown(path, 400)}: cached mesh unreadable ({shown(e)}); re-run the import") from None


@dataclass(frozen=True)
class CatalogStats:
    assets: int
    classes: int
    groups: dict
    sources: dict
    skipped: list

    def to_json(self) -> dict:
        return {
            "assets": self.assets,
            "classes": self.classes,
            "groups": self.groups,
            "sources": self.sources,
            "skipped": self.skipped,
        }


class Catalog:
    """Read access to a catalog folder, plus the writer used by importers.

    ``records`` is in a stable order (sorted by id), so seeded sampling over a catalog is
    reproducible whatever order the importers ran in.
    """

    def __init__(self, root: str | Path, records: Sequence[AssetRecord] = (), skipped: Sequence[dict] = (),
                 *, mesh_cache_size: int = 512):
        self.root = Path(root)
        self._records: dict[str, AssetRecord] = {r.id: r for r in records}
        self._skipped: list[dict] = list(skipped)
        self._sorted: tuple[AssetRecord, ...] | None = None
        self._mesh_cache: OrderedDict[str, MeshData] = OrderedDict()
        self._mesh_cache_size = mesh_cache_size
        self._lock = threading.Lock()

    # ---------------------------------------------------------------- reading

    @classmethod
    def open(cls, root: str | Path) -> "Catalog":
        """Open an existing catalog; a clear error if it is missing or corrupt."""
        root = Path(root)
        index = root / INDEX_NAME
        if not index.is_file():
            raise AssetError(f"{root}: no asset catalog here ({INDEX_NAME} missing); build one with "
                             f"`assist3d assets import sh3d`, `assets import meshes` or `assets procedural`")
        try:
            data = reading.read_json(index, error=AssetError, what="catalog index")
        except AssetError as e:
            raise AssetError(f"{shown(index, 400)}: unreadable catalog index ({reading.problem(e, index)})") from None
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            raise AssetError(f"{index}: not an assist3d catalog index (format field missing)")
        try:
            records = [AssetRecord.from_json(d) for d in data.get("assets", [])]
        except (KeyError, TypeError, ValueError) as e:
            raise AssetError(f"{index}: malformed asset record ({e})") from None
        return cls(root, records, data.get("skipped", []))

    @classmethod
    def open_or_create(cls, root: str | Path) -> "Catalog":
        root = Path(root)
        if (root / INDEX_NAME).is_file():
            return cls.open(root)
        return cls(root)

    @staticmethod
    def exists(root: str | Path) -> bool:
        return (Path(root) / INDEX_NAME).is_file()

    @property
    def records(self) -> tuple[AssetRecord, ...]:
        if self._sorted is None:
            self._sorted = tuple(self._records[k] for k in sorted(self._records))
        return self._sorted

    def __len__(self) -> int:
        return len(self._records)

    def __contains__(self, asset_id: str) -> bool:
        return asset_id in self._records

    def get(self, asset_id: str) -> AssetRecord:
        try:
            return self._records[asset_id]
        except KeyError:
            raise AssetError(f"{self.root}: no asset with id '{shown(asset_id)}'") from None

    def group(self, group: str) -> tuple[AssetRecord, ...]:
        """Records that belong to ``group`` ('floor', 'wall' or 'obj'), in id order."""
        if group not in GROUPS:
            raise AssetError(f"unknown group {group!r}; expected one of {GROUPS}")
        return tuple(r for r in self.records if group in r.groups)

    @property
    def skipped(self) -> list[dict]:
        return list(self._skipped)

    def load_mesh(self, record: AssetRecord | str) -> MeshData:
        """The normalised mesh of an asset (canonical frame), cached in memory (LRU)."""
        rec = self.get(record) if isinstance(record, str) else record
        with self._lock:
            mesh = self._mesh_cache.get(rec.id)
            if mesh is not None:
                self._mesh_cache.move_to_end(rec.id)
                return mesh
        path = inside(self.root, rec.mesh_file, what=f"{self.root / INDEX_NAME}: asset '{shown(rec.id)}' mesh_file",
                      error=AssetError)
        mesh = load_mesh_file(path)
        with self._lock:
            self._mesh_cache[rec.id] = mesh
            while len(self._mesh_cache) > self._mesh_cache_size:
                self._mesh_cache.popitem(last=False)
        return mesh

    def stats(self) -> CatalogStats:
        recs = self.records
        groups = {g: sum(1 for r in recs if g in r.groups) for g in GROUPS}
        sources = dict(sorted(Counter(r.source for r in recs).items()))
        return CatalogStats(
            assets=len(recs),
            classes=len({r.class_name for r in recs}),
            groups=groups,
            sources=sources,
            skipped=[{"path": s["path"], "reason": s["reason"]} for s in self._skipped],
        )

    # ---------------------------------------------------------------- writing

    def add(self, record: AssetRecord, mesh: MeshData) -> AssetRecord:
        """Write ``mesh`` to the cache and register ``record`` (replacing one with the same id).

        Returns the record with ``mesh_file`` and ``triangles`` filled in. Call :meth:`save` to
        persist the index.
        """
        rel = mesh_file_name(record.id)
        save_mesh(self.root / rel, mesh)
        rec = replace(record, mesh_file=rel, triangles=int(len(mesh.faces)))
        with self._lock:
            self._records[rec.id] = rec
            self._sorted = None
            self._mesh_cache.pop(rec.id, None)
        return rec

    def update_record(self, record: AssetRecord) -> None:
        """Replace the metadata of an existing asset (its cached mesh is kept)."""
        with self._lock:
            if record.id not in self._records:
                raise AssetError(f"{self.root}: no asset with id {record.id!r} to update")
            self._records[record.id] = record
            self._sorted = None

    def remove_source(self, source: str, prefix: str = "") -> None:
        """Forget records and skip reports of one source (optionally only ids under ``prefix``)."""
        with self._lock:
            for k in [k for k, r in self._records.items() if r.source == source and r.id.startswith(prefix)]:
                del self._records[k]
            self._skipped = [s for s in self._skipped
                             if not (s.get("source") == source and s.get("id_prefix", "").startswith(prefix))]
            self._sorted = None

    def add_skipped(self, skipped: SkippedAsset | Iterable[SkippedAsset], source: str, id_prefix: str = "") -> None:
        items = [skipped] if isinstance(skipped, SkippedAsset) else list(skipped)
        with self._lock:
            existing = {(s["path"], s.get("source")) for s in self._skipped}
            for s in items:
                if (s.path, source) not in existing:
                    self._skipped.append({"path": s.path, "reason": s.reason, "source": source, "id_prefix": id_prefix})

    def save(self) -> None:
        """Write the index atomically."""
        data = {
            "format": FORMAT,
            "version": VERSION,
            "assets": [r.to_json() for r in self.records],
            "skipped": self._skipped,
        }
        write_json_atomic(self.root / INDEX_NAME, data, indent=None)
