"""Importer of a folder of meshes described by a manifest (Objaverse subsets, ShapeNet, 3D-FUTURE...).

Manifest: CSV (header row) or JSON (a list of objects, or ``{"assets": [...]}``), one row per
mesh with the columns

=============  ===========================================================================
``path``       mesh file relative to the folder (.obj .glb .gltf .ply .stl .off); required
``class``      class name (normalised to lower case); required
``groups``     ``floor``, ``wall``, ``obj`` separated by ``;``, ``|`` or spaces (default: from
               size and name, as for Sweet Home 3D)
``size``       ``w,d,h`` metres (or ``w x d x h``): the bounding box is scaled to exactly this
``height``     metres: uniform scale so the height is this (when ``size`` is not given)
``scale``      uniform factor (default 1: the file is in metres)
``up``         source up axis (default ``+y``: glTF / Objaverse / ShapeNet convention)
``front``      source front axis (default ``+z``)
``elevation``  base height above the floor in metres (wall items), default 0
``id``         stable id within the collection (default: the relative path)
``name``       human-readable name (default: the class)
``license``, ``attribution``  copied into the record
=============  ===========================================================================

Paths that escape the folder (absolute, ``..``, symlinks leading outside) are rejected, and so are
external files a glTF/OBJ references outside the folder. Bad rows and broken meshes are skipped
with a one-line reason; the import goes on.
"""

from __future__ import annotations

import csv
import io
import logging
import os
import posixpath
import re
import time
from dataclasses import dataclass
from pathlib import Path, PurePosixPath, PureWindowsPath
from typing import Any, Sequence

import numpy as np

from ..core.contracts import GROUPS, AssetRecord, MeshData, SkippedAsset
from ..core import reading
from ..core.errors import AssetError, shown
from ..core.fileio import write_json_atomic
from .catalog import Catalog
from .importer import ImportReport, Progress, run_import
from .naming import assign_groups, class_from_name
from .normalize import MeshRejected, axes_rotation, extract_supports, flatten_geometry, normalize_arrays
from .objfile import ObjUnsupported, check_obj_text, obj_arrays

log = logging.getLogger(__name__)

SOURCE = "meshes"
FORMATS = {"obj": "obj", "glb": "glb", "gltf": "gltf", "ply": "ply", "stl": "stl", "off": "off"}
DEFAULT_UP = "+y"
DEFAULT_FRONT = "+z"
MAX_ROWS = 1_000_000  # a manifest larger than this is almost certainly a mistake


@dataclass(frozen=True)
class MeshItem:
    """One manifest row, checked and ready for a worker."""

    folder: str  # resolved folder
    path: str  # relative path, posix
    row: str  # "manifest.csv:row 7" for messages
    asset_id: str
    collection: str
    class_name: str
    name: str
    groups: tuple[str, ...] | None
    size: tuple[float, float, float] | None
    height: float | None
    scale: float | None
    up: str
    front: str
    elevation: float
    license: str
    attribution: str


# --------------------------------------------------------------------------------------------
# Manifest
# --------------------------------------------------------------------------------------------


def read_manifest(manifest: str | os.PathLike) -> list[dict[str, Any]]:
    """Rows of a CSV or JSON manifest as dicts (keys lower-cased); AssetError if unreadable."""
    manifest = Path(manifest)
    text = reading.read_text(manifest, error=AssetError, missing="manifest not found", what="manifest")
    if manifest.suffix.lower() == ".json" or text.lstrip().startswith(("[", "{")):
        data = reading.parse_json(text, manifest, error=AssetError, what="manifest")
        if isinstance(data, dict):
            data = data.get("assets")
        if not isinstance(data, list):
            raise AssetError(f"{manifest}: expected a JSON list of rows or {{\"assets\": [...]}}")
        rows = [{str(k).strip().lower(): v for k, v in r.items()} if isinstance(r, dict) else {"__bad__": r}
                for r in data]
    else:
        reader = csv.DictReader(io.StringIO(text))
        if not reader.fieldnames or "path" not in [f.strip().lower() for f in reader.fieldnames]:
            raise AssetError(f"{manifest}: CSV header must name at least the columns 'path' and 'class'")
        try:
            rows = [{(k or "").strip().lower(): (v.strip() if isinstance(v, str) else v) for k, v in r.items()}
                    for r in reader]
        except csv.Error as e:
            raise AssetError(f"{shown(manifest, 400)}: malformed CSV ({shown(e)})") from None
    if len(rows) > MAX_ROWS:
        raise AssetError(f"{manifest}: {len(rows)} rows, more than the limit of {MAX_ROWS}")
    return rows


def safe_relative_path(folder: Path, path: str) -> str:
    """``path`` as a clean posix path inside ``folder``; raises MeshRejected if it escapes it."""
    if not path or not str(path).strip():
        raise MeshRejected("empty path")
    p = str(path).strip().replace("\\", "/")
    if PurePosixPath(p).is_absolute() or PureWindowsPath(p).is_absolute() or re.match(r"^[A-Za-z]:", p):
        raise MeshRejected(f"path {path!r} is absolute; manifest paths must be relative to the folder")
    parts = PurePosixPath(p).parts
    if ".." in parts:
        raise MeshRejected(f"path {path!r} escapes the folder ('..')")
    rel = posixpath.normpath(p)
    full = (folder / rel).resolve()
    try:
        full.relative_to(folder)
    except ValueError:
        raise MeshRejected(f"path {path!r} leads outside the folder (symlink to {full})") from None
    return rel


def _numbers(value: Any, what: str) -> list[float]:
    if isinstance(value, (list, tuple)):
        items = list(value)
    else:
        items = [x for x in re.split(r"[,;x×\s]+", str(value).strip().lower()) if x]
    try:
        out = [float(x) for x in items]
    except (TypeError, ValueError):
        raise MeshRejected(f"{what} {value!r} is not numeric") from None
    if not all(np.isfinite(out)) or any(x <= 0 for x in out):
        raise MeshRejected(f"{what} {value!r} must be positive numbers")
    return out


def _opt(row: dict, key: str) -> Any:
    v = row.get(key)
    if v is None or (isinstance(v, str) and not v.strip()):
        return None
    return v


def parse_row(row: dict[str, Any], *, folder: Path, collection: str, where: str) -> MeshItem:
    """Check one manifest row; raises MeshRejected with the problem."""
    if "__bad__" in row:
        raise MeshRejected("row is not an object")
    path = _opt(row, "path")
    if path is None:
        raise MeshRejected("no 'path'")
    rel = safe_relative_path(folder, str(path))
    ext = rel.rsplit(".", 1)[-1].lower() if "." in posixpath.basename(rel) else ""
    if ext not in FORMATS:
        raise MeshRejected(f"{rel}: unknown mesh format '.{ext}' (expected one of {', '.join(sorted(FORMATS))})")
    if not (folder / rel).is_file():
        raise MeshRejected(f"{rel}: file not found")
    raw_class = _opt(row, "class") or _opt(row, "category")
    if raw_class is None:
        raise MeshRejected(f"{rel}: no 'class'")
    class_name = class_from_name(str(raw_class))
    groups = None
    g = _opt(row, "groups") or _opt(row, "group")
    if g is not None:
        names = g if isinstance(g, (list, tuple)) else re.split(r"[;|,\s]+", str(g).strip().lower())
        names = [str(n).strip().lower() for n in names if str(n).strip()]
        bad = [n for n in names if n not in GROUPS]
        if bad or not names:
            raise MeshRejected(f"{rel}: groups {g!r}: expected some of {', '.join(GROUPS)}")
        groups = tuple(x for x in GROUPS if x in names)
    size = height = scale = None
    if _opt(row, "size") is not None:
        nums = _numbers(row["size"], "size")
        if len(nums) != 3:
            raise MeshRejected(f"{rel}: size {row['size']!r} must be three numbers w,d,h in metres")
        size = (nums[0], nums[1], nums[2])
    elif all(_opt(row, k) is not None for k in ("width", "depth", "height")):
        size = tuple(_numbers(row[k], k)[0] for k in ("width", "depth", "height"))  # type: ignore[assignment]
    elif _opt(row, "height") is not None:
        height = _numbers(row["height"], "height")[0]
    if _opt(row, "scale") is not None:
        scale = _numbers(row["scale"], "scale")[0]
    up = str(_opt(row, "up") or DEFAULT_UP)
    front = str(_opt(row, "front") or DEFAULT_FRONT)
    try:
        axes_rotation(up, front)
    except ValueError as e:
        raise MeshRejected(f"{rel}: {e}") from None
    try:
        elevation = float(_opt(row, "elevation") or 0.0)
    except (TypeError, ValueError):
        raise MeshRejected(f"{rel}: elevation {row.get('elevation')!r} is not a number") from None
    if not np.isfinite(elevation) or elevation < 0:
        raise MeshRejected(f"{rel}: elevation {elevation} must be >= 0 metres")
    ident = str(_opt(row, "id") or rel)
    ident = "".join(ch if ch.isalnum() or ch in "-_./" else "-" for ch in ident).strip("/")
    return MeshItem(
        folder=str(folder), path=rel, row=where, asset_id=f"{SOURCE}:{collection}/{ident}", collection=collection,
        class_name=class_name, name=str(_opt(row, "name") or raw_class), groups=groups, size=size, height=height,
        scale=scale, up=up, front=front, elevation=elevation, license=str(_opt(row, "license") or ""),
        attribution=str(_opt(row, "attribution") or ""),
    )


# --------------------------------------------------------------------------------------------
# Loading (worker side)
# --------------------------------------------------------------------------------------------


def _folder_resolver(folder: Path, base: str):
    """A trimesh resolver that serves files next to the mesh and refuses anything outside ``folder``."""
    from trimesh.resolvers import Resolver

    class FolderResolver(Resolver):
        def __init__(self, base: str):
            self.base = base

        def get(self, name: str) -> bytes:
            rel = safe_relative_path(folder, posixpath.join(self.base, str(name).replace("\\", "/")))
            return reading.read_bytes(folder / rel, error=AssetError)

        def write(self, name: str, data: bytes) -> None:
            raise OSError("read-only folder")

        def namespaced(self, namespace: str) -> "FolderResolver":
            return FolderResolver(posixpath.join(self.base, namespace))

        def keys(self):
            return iter(())

    return FolderResolver(base)


def convert_item(item: MeshItem) -> tuple[AssetRecord, MeshData] | SkippedAsset:
    """Load and normalise one mesh; a SkippedAsset with the reason on failure (never raises for
    bad content, so one file can never abort a whole import)."""
    label = f"{Path(item.folder) / item.path} ({item.row})"
    try:
        return _convert(item, label)
    except Exception as e:  # a loader failure on strange data: report it, keep importing
        log.warning("meshes: unexpected error on %s", shown(label, 400), exc_info=True)
        return SkippedAsset(label, f"unexpected error ({type(e).__name__}: {e})")


def _convert(item: MeshItem, label: str) -> tuple[AssetRecord, MeshData] | SkippedAsset:
    import trimesh

    folder = Path(item.folder)
    try:
        data = reading.read_bytes(folder / item.path, error=AssetError)
        if not data.strip():
            raise MeshRejected("empty file")
        ext = FORMATS[item.path.rsplit(".", 1)[-1].lower()]
        reading.check_mesh_counts(data, ext, folder / item.path, error=AssetError)
        resolver = _folder_resolver(folder, posixpath.dirname(item.path))
        arrays = None
        if ext == "obj":
            check_obj_text(data, label)
            try:
                arrays = obj_arrays(data, resolver.get)
            except ObjUnsupported as e:
                log.debug("meshes: %s: %s, using trimesh", shown(label, 400), e)
        if arrays is None:
            try:
                loaded = trimesh.load(io.BytesIO(data), file_type=ext, force="scene", process=False, resolver=resolver)
            except MeshRejected:
                raise
            except Exception as e:  # loaders raise many exception types on malformed files
                raise MeshRejected(f"unreadable {ext} file ({type(e).__name__}: {e})") from None
            arrays = flatten_geometry(loaded)
            if len(arrays[1]) == 0 and len(getattr(loaded, "geometry", {}) or {}) > 0:
                raise MeshRejected("no triangles: the file holds only lines or points")
        v, f, c = arrays
        if len(f) > reading.MAX_MESH_TRIANGLES or len(v) > reading.MAX_MESH_VERTICES:  # before normalising
            raise MeshRejected(f"{len(v):,} vertices and {len(f):,} triangles, more than the "
                               f"{reading.MAX_MESH_VERTICES:,} / {reading.MAX_MESH_TRIANGLES:,} a mesh may have")
        rotation = axes_rotation(item.up, item.front)
        scale = item.scale
        if item.size is None and item.height is not None and len(f):
            z = (v[np.unique(f)] @ rotation.T)[:, 2]
            h = float(z.max() - z.min()) if np.all(np.isfinite(z)) else 0.0
            if h > 0:
                scale = item.height / h
        norm = normalize_arrays(v, f, c, rotation=rotation, size=item.size, scale=scale)
    except MeshRejected as e:
        return SkippedAsset(label, str(e))
    except AssetError as e:
        return SkippedAsset(label, reading.problem(e, folder / item.path))
    except OSError as e:
        return SkippedAsset(label, f"unreadable file ({e})")
    w, d, h = norm.size
    if max(w, d, h) > 20.0 or max(w, d, h) < 0.005:
        return SkippedAsset(label, f"implausible size {w:.3g} x {d:.3g} x {h:.3g} m: give 'size', 'height' or 'scale'")
    groups = item.groups or assign_groups(norm.size, elevation=item.elevation, name=item.name)
    record = AssetRecord(
        id=item.asset_id, source=SOURCE, name=item.name, class_name=item.class_name, groups=groups, size=norm.size,
        supports=extract_supports(norm.mesh), license=item.license, attribution=item.attribution,
        family=item.collection, elevation=item.elevation,
        extra={"collection": item.collection, "path": item.path, "up": item.up, "front": item.front},
    )
    return record, norm.mesh


# --------------------------------------------------------------------------------------------
# Driver
# --------------------------------------------------------------------------------------------


def import_meshes(catalog: Catalog, folder: str | os.PathLike, manifest: str | os.PathLike, *,
                  collection: str | None = None, workers: int | None = None, save_every: int = 50,
                  progress: Progress | None = None) -> ImportReport:
    """Import the meshes a manifest lists from ``folder`` into ``catalog`` and save its index.

    Ids are ``meshes:<collection>/<id or path>``; ``collection`` defaults to the folder name.
    Re-running replaces the collection's records (idempotent). Raises AssetError only when the
    folder or the manifest as a whole is unusable; bad rows are skipped with reasons.
    """
    t0 = time.perf_counter()
    root = Path(folder).expanduser()
    if not root.is_dir():
        raise AssetError(f"{root}: mesh folder not found")
    root = root.resolve()
    collection = collection or root.name
    collection = "".join(ch if ch.isalnum() or ch in "-_." else "-" for ch in collection) or "meshes"
    rows = read_manifest(manifest)
    items: list[MeshItem] = []
    skipped: list[SkippedAsset] = []
    seen: set[str] = set()
    mname = Path(manifest).name
    for i, row in enumerate(rows, start=2 if Path(manifest).suffix.lower() == ".csv" else 1):
        where = f"{mname}:row {i}"
        try:
            item = parse_row(row, folder=root, collection=collection, where=where)
        except MeshRejected as e:
            skipped.append(SkippedAsset(f"{Path(manifest)}:row {i}", str(e)))
            continue
        if item.asset_id in seen:
            skipped.append(SkippedAsset(f"{Path(manifest)}:row {i}", f"duplicate id {item.asset_id!r}"))
            continue
        seen.add(item.asset_id)
        items.append(item)
    prefix = f"{SOURCE}:{collection}/"
    catalog.remove_source(SOURCE, prefix)
    if skipped:
        catalog.add_skipped(skipped, SOURCE, prefix)
    log.info("meshes: %d rows, %d usable, from %s", len(rows), len(items), manifest)
    return run_import(catalog, items, convert_item, source=SOURCE, part_of=lambda it: it.collection,
                      label_of=lambda it: it.path, parts=[collection], skipped=skipped, workers=workers,
                      save_every=save_every, progress=progress, started=t0)


def write_manifest(path: str | os.PathLike, rows: Sequence[dict[str, Any]]) -> None:
    """Write manifest rows as JSON (atomically); a helper for scripts that build manifests."""
    write_json_atomic(path, {"assets": list(rows)})
