"""Sweet Home 3D furniture importer.

Reads ``.sh3f`` furniture libraries (zips with ``PluginFurnitureCatalog.properties``) and the
default catalog inside ``sweethome3d.jar`` (``DefaultFurnitureCatalog.properties``) straight from
the zip: OBJ, MTL and textures are resolved inside the archive, nothing is extracted to disk.

Per model: apply ``modelRotation`` (3x3, row-major, in the OBJ frame), convert the OBJ convention
(y up, front +z) to the canonical frame (z up, front -y), scale the bounding box to
``width x depth x height`` (cm -> m), centre the footprint, base at z = 0. Supports come from
``dropOnTopElevation`` when the catalog gives one, plus the mesh's upward faces. Doors and windows
(``doorOrWindow=true``) are skipped: they belong in walls, not in the room as objects.
"""

from __future__ import annotations

import io
import logging
import os
import posixpath
import re
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
import shapely

from ..core.contracts import AssetRecord, MeshData, SkippedAsset
from ..core.errors import shown
from .catalog import Catalog
from .importer import ImportReport, Progress, run_import
from .naming import assign_groups, class_from_name, wall_mount
from .normalize import (MeshRejected, axes_rotation, extract_supports, flatten_geometry, normalize_arrays,
                        support_at_height)
from .objfile import ObjUnsupported, check_obj_text, obj_arrays
from .properties import parse_properties

log = logging.getLogger(__name__)

OUTDOOR_CATEGORIES = frozenset({"Exterior", "Vehicles"})
SUBSTRUCTURE_DEPTH = 0.10  # m below a declared dropOnTopElevation surface

SOURCE = "sh3d"
SH3D_FURNITURE_DIR = Path("/usr/share/sweethome3d/furniture")
SH3D_JAR = Path("/usr/share/sweethome3d/sweethome3d.jar")
PLUGIN_PROPERTIES = "PluginFurnitureCatalog.properties"
DEFAULT_PROPERTIES = "DefaultFurnitureCatalog.properties"
OBJ_ROTATION = axes_rotation(up="+y", front="+z")  # OBJ frame -> canonical frame


def default_sh3d_paths() -> list[Path]:
    """Every ``.sh3f`` under the Debian furniture folder plus the default catalog jar, if installed."""
    paths = sorted(SH3D_FURNITURE_DIR.glob("*.sh3f")) if SH3D_FURNITURE_DIR.is_dir() else []
    if SH3D_JAR.is_file():
        paths.append(SH3D_JAR)
    return paths


def expand_paths(paths: Iterable[str | os.PathLike]) -> list[Path]:
    """Files as given; folders replaced by the ``.sh3f`` files they hold (sorted)."""
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            out.extend(sorted(p.glob("*.sh3f")))
        else:
            out.append(p)
    return out


def catalog_stem(path: Path) -> str:
    """Name used in ids: the file stem; the jar's default catalog is ``DefaultFurnitureCatalog``."""
    return "DefaultFurnitureCatalog" if path.suffix.lower() == ".jar" else path.stem


def short_license(text: str, stem: str) -> str:
    """SPDX-like licence id of a catalog from its ``license`` line."""
    t = text.lower()
    if "public domain" in t or "cc-0" in stem.lower() or "cc0" in t:
        return "CC0-1.0"
    if "gnu gpl" in t and "cc-by" in t:
        return "GPL-2.0-or-later OR CC-BY-3.0"
    if "attribution" in t or "cc-by" in t:
        return "CC-BY-3.0-US" if "united states" in t else "CC-BY-3.0"
    return text.strip() or "unknown"


# --------------------------------------------------------------------------------------------
# Reading catalogs
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Sh3dEntry:
    """One model of a catalog, ready to be converted in a worker process."""

    archive: str  # path of the .sh3f / .jar
    stem: str
    index: int  # N of the key#N properties
    asset_id: str
    props: dict[str, str]
    base_dir: str  # folder of the properties file inside the zip
    license: str
    license_text: str
    catalog_name: str

    @property
    def label(self) -> str:
        return f"{self.archive}!{self.props.get('model', '').lstrip('/')} (#{self.index} {self.props.get('name', '?')!r})"


@dataclass
class CatalogEntries:
    entries: list[Sh3dEntry] = field(default_factory=list)
    skipped: list[SkippedAsset] = field(default_factory=list)


def _find_properties(zf: zipfile.ZipFile) -> str | None:
    names = zf.namelist()
    if PLUGIN_PROPERTIES in names:
        return PLUGIN_PROPERTIES
    for n in names:
        if n == DEFAULT_PROPERTIES or n.endswith("/" + DEFAULT_PROPERTIES):
            return n
    for n in names:
        if posixpath.basename(n) == PLUGIN_PROPERTIES:
            return n
    return None


def _safe_id(text: str) -> str:
    s = text.split("#", 1)[-1] if "#" in text else text
    s = "".join(ch if ch.isalnum() or ch in "-_." else "-" for ch in s.strip())
    return s.strip("-") or "model"


def read_catalog(path: str | os.PathLike) -> CatalogEntries:
    """Parse one catalog file into entries and skip reports (never raises for bad content)."""
    path = Path(path)
    out = CatalogEntries()
    stem = catalog_stem(path)
    try:
        zf = zipfile.ZipFile(path)
    except FileNotFoundError:
        out.skipped.append(SkippedAsset(str(path), "catalog file not found"))
        return out
    except (zipfile.BadZipFile, OSError) as e:
        out.skipped.append(SkippedAsset(str(path), f"not a readable zip archive ({e})"))
        return out
    with zf:
        prop_name = _find_properties(zf)
        if prop_name is None:
            out.skipped.append(SkippedAsset(str(path), f"no {PLUGIN_PROPERTIES} or {DEFAULT_PROPERTIES} inside"))
            return out
        try:
            data = zf.read(prop_name)
        except (zipfile.BadZipFile, OSError, EOFError, zipfile.LargeZipFile) as e:
            out.skipped.append(SkippedAsset(f"{path}!{prop_name}", f"unreadable properties ({e})"))
            return out
    props = parse_properties(data, source=f"{path}!{prop_name}")
    for err in props.errors:
        where, _, reason = err.rpartition(": ")
        out.skipped.append(SkippedAsset(where, f"broken properties line: {reason}"))
    license_text = props.values.get("license", "")
    lic = short_license(license_text, stem)
    cat_name = props.values.get("name", stem)
    base_dir = posixpath.dirname(prop_name)
    seen: dict[str, int] = {}
    for index, entry in props.indexed.items():
        if "model" not in entry and "name" not in entry:
            continue  # e.g. a stray key#N that is not a model
        raw = entry.get("id") or entry.get("model", "").rsplit("/", 1)[-1].rsplit(".", 1)[0] or str(index)
        sid = _safe_id(raw)
        if sid in seen:
            sid = f"{sid}~{index}"
        seen[sid] = index
        out.entries.append(Sh3dEntry(
            archive=str(path), stem=stem, index=index, asset_id=f"{SOURCE}:{stem}/{sid}", props=entry,
            base_dir=base_dir, license=lic, license_text=license_text, catalog_name=cat_name,
        ))
    return out


# --------------------------------------------------------------------------------------------
# Converting one model (runs in worker processes)
# --------------------------------------------------------------------------------------------

_ZIPS: dict[tuple[int, str], tuple[zipfile.ZipFile, dict[str, str]]] = {}


def _open_zip(path: str) -> tuple[zipfile.ZipFile, dict[str, str]]:
    """An open archive and its lower-case name map, cached per process (a forked worker must not
    share the parent's file offset)."""
    key = (os.getpid(), path)
    got = _ZIPS.get(key)
    if got is None:
        zf = zipfile.ZipFile(path)
        got = (zf, {n.lower(): n for n in zf.namelist()})
        _ZIPS[key] = got
    return got


def _zip_resolver(zf: zipfile.ZipFile, names: dict[str, str], folder: str, extra: dict[str, bytes] | None = None):
    """A trimesh resolver reading MTL files and textures next to the OBJ inside the zip.

    ``extra`` serves generated files (the built-in material library) by exact name.
    """
    from trimesh.resolvers import Resolver

    extra = extra or {}

    class ZipFolderResolver(Resolver):
        def __init__(self, folder: str):
            self.folder = folder

        def get(self, name: str) -> bytes:
            if name in extra:
                return extra[name]
            rel = posixpath.normpath(posixpath.join(self.folder, name.replace("\\", "/"))).lstrip("/")
            real = names.get(rel.lower()) or names.get(posixpath.basename(rel).lower())
            if real is None and rel.lower().endswith(".mtl"):
                # a renamed material file: use the folder's only .mtl, if there is exactly one
                folder = posixpath.dirname(rel).lower()
                mtls = [n for k, n in names.items() if k.endswith(".mtl") and posixpath.dirname(k) == folder]
                real = mtls[0] if len(mtls) == 1 else None
            if real is None:
                raise KeyError(f"{name!r} not in archive")
            return zf.read(real)

        def write(self, name: str, data: bytes) -> None:
            raise OSError("read-only archive")

        def namespaced(self, namespace: str) -> "ZipFolderResolver":
            return ZipFolderResolver(posixpath.join(self.folder, namespace))

        def keys(self):
            return iter(())

    return ZipFolderResolver(folder)


# Sweet Home 3D's own OBJ files (the default catalog) use named materials without an MTL file;
# these are our approximations of what the names mean (r, g, b in 0..1).
NAMED_COLOURS: dict[str, tuple[float, float, float]] = {
    "white": (0.95, 0.95, 0.95), "flwhite": (0.93, 0.93, 0.92), "flwhite1": (0.93, 0.93, 0.92),
    "archwhite": (0.92, 0.91, 0.88), "archwhite2": (0.9, 0.89, 0.86), "offwhite": (0.92, 0.9, 0.85),
    "black": (0.05, 0.05, 0.05), "flblack": (0.06, 0.06, 0.06), "grey": (0.5, 0.5, 0.5), "flgrey": (0.55, 0.55, 0.55),
    "ltgrey": (0.75, 0.75, 0.75), "flltgrey": (0.8, 0.8, 0.8), "dkgrey": (0.3, 0.3, 0.3), "fldkgrey": (0.3, 0.3, 0.3),
    "dkdkgrey": (0.15, 0.15, 0.15), "fldkdkgrey": (0.15, 0.15, 0.15), "silver": (0.75, 0.75, 0.78),
    "bluegrey": (0.45, 0.5, 0.6), "ship2": (0.6, 0.6, 0.65), "flblonde": (0.85, 0.72, 0.5),
    "flyellow": (0.9, 0.8, 0.3), "yellow": (0.95, 0.9, 0.2), "yellowbrt": (1.0, 0.95, 0.3),
    "yellow_green": (0.6, 0.8, 0.2), "green": (0.2, 0.6, 0.2), "amber": (0.8, 0.55, 0.15),
    "bone": (0.9, 0.87, 0.78), "bone2": (0.88, 0.85, 0.76), "teeth": (0.95, 0.95, 0.9), "iris": (0.35, 0.35, 0.7),
    "blue": (0.15, 0.3, 0.8), "dkblue": (0.1, 0.15, 0.45), "sky_blue": (0.5, 0.75, 0.95), "bluteal": (0.1, 0.5, 0.55),
    "lavendar": (0.7, 0.6, 0.9), "red": (0.85, 0.1, 0.1), "dkred": (0.5, 0.05, 0.05), "ruby": (0.7, 0.05, 0.15),
    "redwood": (0.5, 0.2, 0.12), "brown": (0.45, 0.28, 0.15), "flbrown": (0.45, 0.3, 0.18),
    "flltbrown": (0.6, 0.45, 0.3), "brownlips": (0.5, 0.3, 0.25), "brzskin": (0.6, 0.4, 0.25),
    "flesh": (0.95, 0.75, 0.65), "tan": (0.8, 0.68, 0.5), "fltan": (0.82, 0.7, 0.55), "lighttan": (0.85, 0.78, 0.62),
    "lighttan2": (0.85, 0.78, 0.62), "lighttannew": (0.85, 0.78, 0.62), "sand_stone": (0.8, 0.72, 0.58),
    "jetflame": (1.0, 0.5, 0.1), "florange": (0.95, 0.55, 0.1), "orange": (0.95, 0.55, 0.1),
}
BUILTIN_MTL = "__assist3d_named_colours__.mtl"


def builtin_mtl(material_names: Iterable[str]) -> bytes:
    """MTL text giving each known named material (``white``, ``flblonde``, ``white.001``...) its
    colour; empty when none is known."""
    lines = []
    for name in sorted(set(material_names)):
        key = name.lower().split(".", 1)[0]
        rgb = NAMED_COLOURS.get(key)
        if rgb is not None:
            lines.append(f"newmtl {name}\nKd {rgb[0]:.3f} {rgb[1]:.3f} {rgb[2]:.3f}\n")
    return "".join(lines).encode("latin-1")


def _float(props: dict[str, str], key: str) -> float | None:
    v = props.get(key)
    if v is None or not v.strip():
        return None
    try:
        x = float(v.strip())
    except ValueError:
        raise MeshRejected(f"{key}={v!r} is not a number") from None
    if not np.isfinite(x):
        raise MeshRejected(f"{key}={v!r} is not finite")
    return x


def _model_rotation(props: dict[str, str]) -> np.ndarray:
    """Canonical rotation = OBJ->canonical axes after the catalog's ``modelRotation``."""
    text = props.get("modelRotation", "").strip()
    if not text:
        return OBJ_ROTATION
    try:
        m = np.array([float(x) for x in text.replace(",", " ").split()], dtype=np.float64)
    except ValueError:
        raise MeshRejected(f"modelRotation={text!r} is not 9 numbers") from None
    if m.size != 9 or not np.all(np.isfinite(m)):
        raise MeshRejected(f"modelRotation={text!r} is not 9 numbers")
    return OBJ_ROTATION @ m.reshape(3, 3)


def _load_arrays(entry: Sh3dEntry, *, fast: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices (V, 3), faces (F, 3) and face colours (F, 3) uint8 of an entry's OBJ (OBJ frame).

    The fast reader (:mod:`.objfile`) handles the common OBJ subset; files it does not support go
    through trimesh's complete loader (``fast=False`` forces that path).
    """
    import trimesh

    model = entry.props.get("model", "").strip()
    if not model:
        raise MeshRejected("no model# key")
    zf, names = _open_zip(entry.archive)
    candidates = [model.lstrip("/"), posixpath.join(entry.base_dir, model.lstrip("/"))]
    real = next((names[c.lower()] for c in candidates if c.lower() in names), None)
    if real is None:
        raise MeshRejected(f"model file {model!r} missing from the archive")
    ext = real.rsplit(".", 1)[-1].lower()
    if ext != "obj":
        raise MeshRejected(f"model file {model!r}: unsupported format .{ext} (expected .obj)")
    data = zf.read(real)
    if not data.strip():
        raise MeshRejected(f"model file {model!r} is empty")
    check_obj_text(data, entry.label)
    extra: dict[str, bytes] = {}
    if b"mtllib" not in data:
        mtl = builtin_mtl(m.decode("latin-1") for m in re.findall(rb"^\s*usemtl\s+(\S+)", data, re.M))
        if mtl:
            extra[BUILTIN_MTL] = mtl
            data = f"mtllib {BUILTIN_MTL}\n".encode() + data
    resolver = _zip_resolver(zf, names, posixpath.dirname(real), extra)
    if fast:
        try:
            return obj_arrays(data, resolver.get)
        except ObjUnsupported as e:
            log.debug("sh3d: %s: %s, using trimesh", shown(entry.label, 400), e)
    try:
        loaded = trimesh.load(io.BytesIO(data), file_type="obj", resolver=resolver,
                              force="scene", process=False, group_material=True, skip_materials=False)
    except Exception as e:  # trimesh raises many types on malformed files
        raise MeshRejected(f"model file {model!r} unreadable ({type(e).__name__}: {e})") from None
    v, f, c = flatten_geometry(loaded)
    if len(f) == 0 and len(loaded.geometry) > 0:
        raise MeshRejected("no triangles: the file holds only lines or points")
    return v, f, c


def convert_entry(entry: Sh3dEntry) -> tuple[AssetRecord, MeshData] | SkippedAsset:
    """Load, normalise and describe one model; a :class:`SkippedAsset` with a reason on failure.

    Never raises for bad content: an unexpected error in a third-party loader is reported as
    the model's skip reason too, so one model can never abort a whole import.
    """
    try:
        return _convert(entry)
    except MeshRejected as e:
        return SkippedAsset(entry.label, str(e))
    except (zipfile.BadZipFile, OSError, EOFError, zipfile.LargeZipFile) as e:
        return SkippedAsset(entry.label, f"archive unreadable ({e})")
    except Exception as e:  # a bug or a loader failure on strange data: report it, keep importing
        log.warning("sh3d: unexpected error on %s", shown(entry.label, 400), exc_info=True)
        return SkippedAsset(entry.label, f"unexpected error ({type(e).__name__}: {e})")


def _convert(entry: Sh3dEntry) -> tuple[AssetRecord, MeshData]:
    p = entry.props
    if p.get("doorOrWindow", "false").strip().lower() == "true":
        raise MeshRejected("door or window: belongs in a wall opening, not placed as an object")
    name = p.get("name", "").strip()
    if not name:
        raise MeshRejected("no name# key")
    dims = [_float(p, k) for k in ("width", "depth", "height")]
    if any(d is None or d <= 0 for d in dims):
        raise MeshRejected(f"width/depth/height must be positive numbers (got {dims})")
    size_m = tuple(float(d) / 100.0 for d in dims)  # type: ignore[arg-type]
    elevation = max(0.0, (_float(p, "elevation") or 0.0) / 100.0)
    drop = _float(p, "dropOnTopElevation")
    rotation = _model_rotation(p)
    v, f, c = _load_arrays(entry)
    norm = normalize_arrays(v, f, c, rotation=rotation, size=size_m)
    mesh = norm.mesh
    category = p.get("category", "").strip()
    supports = extract_supports(mesh)
    drop_height = None
    if drop is not None and drop > 0:
        drop_height = drop * norm.size[2] if drop <= 1.0 else drop / 100.0
        drop_height = min(drop_height, norm.size[2])
        top = support_at_height(mesh, drop_height)
        # Surfaces found just under the declared top (a pool table's cushion bed under its felt)
        # are sub-structure, not places to put things: objects there would cut into the top.
        top_poly = shapely.Polygon(top.polygon) if len(top.polygon) >= 3 else None
        supports = (top,) + tuple(
            s for s in supports
            if abs(s.height - drop_height) > 0.03
            and not (drop_height - SUBSTRUCTURE_DEPTH < s.height < drop_height and top_poly is not None
                     and len(s.polygon) >= 3 and shapely.Polygon(s.polygon).intersects(top_poly)))
    if category in OUTDOOR_CATEGORIES:
        supports = ()  # pools and cars are not furniture to put things on in a room
    groups = assign_groups(norm.size, elevation=elevation, name=name, category=category)
    creator = p.get("creator", "").strip()
    attribution = f"{creator or 'unknown author'}, {entry.catalog_name} (Sweet Home 3D), {entry.license}"
    extra: dict = {"catalog": entry.stem, "index": entry.index, "model": p.get("model", "").lstrip("/")}
    if drop_height is not None:
        extra["drop_on_top_height"] = round(drop_height, 6)
    mount = wall_mount(name, category)
    if "wall" in groups:
        extra["mount"] = mount or "wall"
    if p.get("tags"):
        extra["tags"] = [t.strip() for t in p["tags"].split(",") if t.strip()]
    if not p.get("movable", "true").strip().lower() == "true":
        extra["movable"] = False
    record = AssetRecord(
        id=entry.asset_id, source=SOURCE, name=name, class_name=class_from_name(name), groups=groups,
        size=norm.size, supports=supports, license=entry.license, attribution=attribution,
        family=category, elevation=elevation, extra=extra,
    )
    return record, mesh


# --------------------------------------------------------------------------------------------
# Import driver
# --------------------------------------------------------------------------------------------


def _model_size(entry: Sh3dEntry) -> int:
    try:
        zf, names = _open_zip(entry.archive)
        real = names.get(entry.props.get("model", "").lstrip("/").lower())
        return zf.getinfo(real).file_size if real else 0
    except (OSError, KeyError, zipfile.BadZipFile):
        return 0


def import_sh3d(catalog: Catalog, paths: Sequence[str | os.PathLike] | None = None, *, workers: int | None = None,
                save_every: int = 50, progress: Progress | None = None) -> ImportReport:
    """Import Sweet Home 3D catalogs into ``catalog`` and save its index.

    ``paths``: ``.sh3f`` files, ``.jar`` files or folders of ``.sh3f`` (default:
    :func:`default_sh3d_paths`). Each catalog's previous records are replaced (idempotent). The
    index is saved every ``save_every`` assets and at the end, so a killed import keeps complete
    entries only. ``workers`` processes convert models (default: the CPU count; 1 = in-process).
    ``progress(done, total, label)`` is called after each model.
    """
    t0 = time.perf_counter()
    files = expand_paths(paths) if paths else default_sh3d_paths()
    entries: list[Sh3dEntry] = []
    skipped: list[SkippedAsset] = []
    per_catalog: dict[str, list[SkippedAsset]] = {}
    stems: list[str] = []
    for f in files:
        got = read_catalog(f)
        stem = catalog_stem(f)
        if stem not in stems:
            stems.append(stem)
        entries.extend(got.entries)
        per_catalog.setdefault(stem, []).extend(got.skipped)
        skipped.extend(got.skipped)
    for stem in stems:
        catalog.remove_source(SOURCE, f"{SOURCE}:{stem}/")
        if per_catalog[stem]:
            catalog.add_skipped(per_catalog[stem], SOURCE, f"{SOURCE}:{stem}/")
    log.info("sh3d: %d models in %d catalogs", len(entries), len(files))
    # biggest models first so the pool stays busy; results are registered by id (order-free)
    entries.sort(key=lambda e: (-_model_size(e), e.asset_id))
    return run_import(catalog, entries, convert_entry, source=SOURCE, part_of=lambda e: e.stem,
                      label_of=lambda e: e.props.get("name", e.asset_id), parts=stems, skipped=skipped,
                      workers=workers, save_every=save_every, progress=progress, started=t0)
