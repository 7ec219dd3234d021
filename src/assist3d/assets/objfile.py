"""A fast reader for the common subset of Wavefront OBJ (what Sweet Home 3D catalogs hold).

``parse_obj`` reads positions, UVs and polygon faces (fan-triangulated) with their ``usemtl``
material with byte-level splits and numpy conversions over whole blocks instead of a Python
loop per token. It handles ``v``, ``vt``, ``f`` with the ``a``, ``a/b``, ``a//c`` and ``a/b/c``
corner forms, and ``usemtl``/``mtllib``; anything else it does not understand (negative
indices, line continuations, non-numeric fields) raises
:class:`ObjUnsupported` so the caller can fall back to trimesh's complete loader. What no loader
should accept raises :class:`~.normalize.MeshRejected` (the importers skip and report it): a face
that references a vertex the file does not define, and a file cut inside its last record
(:func:`check_obj_text`).
``parse_mtl`` reads ``newmtl``, ``Kd`` and ``map_Kd``; ``face_colors`` turns them into one colour
per face (the texture sampled at each face's UV centroid, else ``Kd``, else grey).
"""

from __future__ import annotations

import io
import logging
import posixpath
import warnings
import zipfile
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..core.errors import shown
from .normalize import NEUTRAL_GREY, MeshRejected, image_array, sample_texture

log = logging.getLogger(__name__)

class ObjUnsupported(ValueError):
    """The file uses an OBJ feature this reader leaves to the complete (slower) loader."""


@dataclass(frozen=True)
class ObjData:
    """Arrays of an OBJ file: vertices (V, 3) float64, uv (T, 2) float64, faces (F, 3) int64
    (0-based), face_uv (F, 3) int64 (-1 = no UV), face_material (F,) int64 (-1 = none),
    material names and the ``mtllib`` file names."""

    vertices: np.ndarray
    uv: np.ndarray
    faces: np.ndarray
    face_uv: np.ndarray
    face_material: np.ndarray
    material_names: tuple[str, ...]
    mtllibs: tuple[str, ...]


@dataclass(frozen=True)
class ObjMaterial:
    kd: np.ndarray | None  # (3,) float64 in 0..255
    texture: str | None  # map_Kd file name


def _numbers(blob: bytes, dtype: type) -> np.ndarray:
    """All numbers of a whitespace-separated blob (C parser); ObjUnsupported if one is not a number."""
    if not blob.strip():
        return np.zeros(0, dtype=dtype)

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy warns (instead of failing) on a bad token
        try:
            return np.fromstring(blob, dtype=dtype, sep=" ")
        except (ValueError, DeprecationWarning):
            raise ObjUnsupported("a line holds something that is not a number") from None


def _floats(lines: list[bytes], width: int, what: str) -> np.ndarray:
    """(len(lines), width) float64 from lines holding at least ``width`` numbers each."""
    if not lines:
        return np.zeros((0, width))
    values = _numbers(b"\n".join(lines), np.float64)
    if len(values) != width * len(lines):
        rows = [line.split() for line in lines]
        if any(len(r) < width for r in rows):
            raise ObjUnsupported(f"a '{what}' line has fewer than {width} numbers")
        values = _numbers(b"\n".join(b" ".join(r[:width]) for r in rows), np.float64)
        if len(values) != width * len(lines):
            raise ObjUnsupported(f"a '{what}' line holds something that is not a number")
    return values.reshape(-1, width)


def _corners(joined: bytes, n_lines: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Parse "\n"-joined face lines: corners per line (n_lines,), and per corner the position and
    UV index (1-based; UV 0 = none). Corner forms ``a``, ``a/b``, ``a//c``, ``a/b/c`` may mix."""
    j = joined.replace(b"//", b"/0/")
    a = np.frombuffer(j, dtype=np.uint8)
    sep = (a == 32) | (a == 9) | (a == 10)
    start = ~sep & np.concatenate([[True], sep[:-1]])
    token = np.cumsum(start) - 1
    n_tokens = int(start.sum())
    slashes = np.bincount(token[(a == 47) & ~sep], minlength=n_tokens)
    fields = slashes + 1
    values = _numbers(j.replace(b"/", b" "), np.int64)
    if len(values) != int(fields.sum()):
        raise ObjUnsupported("a face corner is not of the form a, a/b, a//c or a/b/c")
    offset = np.cumsum(fields) - fields
    pos = values[offset]
    uv = np.where(fields >= 2, values[np.minimum(offset + 1, len(values) - 1)], 0)
    line = np.cumsum(a == 10)
    counts = np.bincount(line[start], minlength=n_lines)[:n_lines]
    return counts, pos, uv


def parse_obj(data: bytes) -> ObjData:
    """Parse OBJ bytes; raises :class:`ObjUnsupported` for what it leaves to trimesh.

    Cost: a few passes over the bytes in C (split, numpy parsing) plus one Python comprehension
    per line kind; no Python work per number.
    """
    if b"\\\n" in data or b"\\\r\n" in data:
        raise ObjUnsupported("line continuations")
    if b"\r" in data:
        data = data.replace(b"\r", b"")
    lines = data.split(b"\n")
    if b"\n " in data or b"\n\t" in data or data[:1] in (b" ", b"\t"):
        lines = [line.lstrip() for line in lines]
    v_lines = [line[2:] for line in lines if line[:2] == b"v "]
    vt_lines = [line[3:] for line in lines if line[:3] == b"vt "]
    if any(b"#" in line for line in v_lines) or any(b"#" in line for line in vt_lines):
        v_lines = [line.split(b"#", 1)[0] for line in v_lines]
        vt_lines = [line.split(b"#", 1)[0] for line in vt_lines]
    vertices = _floats(v_lines, 3, "v")
    uv = _floats(vt_lines, 2, "vt")
    names: list[str] = []
    f_lines: list[bytes] = []
    line_material: list[int] = []
    material = -1
    for line in lines:
        head = line[:2]
        if head == b"f ":
            f_lines.append(line[2:])
            line_material.append(material)
        elif head == b"us" and line.startswith(b"usemtl"):
            name = line[6:].decode("latin-1").strip()
            if name not in names:
                names.append(name)
            material = names.index(name)
    mtllibs = tuple(line[6:].decode("latin-1").strip() for line in lines if line[:7] in (b"mtllib ", b"mtllib\t"))
    if not f_lines:
        empty = np.zeros((0, 3), dtype=np.int64)
        return ObjData(vertices, uv, empty, empty.copy(), np.zeros(0, dtype=np.int64), tuple(names), mtllibs)
    joined = b"\n".join(f_lines)
    if b"#" in joined:
        f_lines = [line.split(b"#", 1)[0] for line in f_lines]
        joined = b"\n".join(f_lines)
    if b"-" in joined:
        raise ObjUnsupported("negative (relative) indices")
    counts, pos, tex = _corners(joined, len(f_lines))
    pos, tex = pos - 1, tex - 1
    if len(pos) and pos.min() < 0:
        raise MeshRejected("a face uses vertex index 0 (OBJ counts vertices from 1): corrupt file")
    if len(pos) and pos.max() >= len(vertices):
        raise MeshRejected(f"a face references vertex {int(pos.max()) + 1} but the file defines only {len(vertices)} "
                           "vertices: truncated or corrupt file")
    if len(uv) == 0 or (tex.max(initial=-1) >= len(uv)):
        tex = np.full(len(pos), -1, dtype=np.int64)
    # fan triangulation of every polygon with at least 3 corners
    keep = counts >= 3
    starts = np.cumsum(counts) - counts
    n_tri = np.where(keep, counts - 2, 0)
    poly = np.repeat(np.arange(len(counts)), n_tri)
    k = np.arange(int(n_tri.sum())) - np.repeat(np.cumsum(n_tri) - n_tri, n_tri)
    c0 = starts[poly]
    idx = np.stack([c0, c0 + k + 1, c0 + k + 2], axis=1)
    return ObjData(vertices=vertices, uv=uv, faces=pos[idx], face_uv=tex[idx],
                   face_material=np.asarray(line_material, dtype=np.int64)[poly], material_names=tuple(names),
                   mtllibs=mtllibs)


#: Fewest values a complete record of each kind holds (``vt`` may give only u).
_MIN_VALUES: dict[bytes, int] = {b"v": 3, b"vn": 3, b"vt": 1, b"f": 3}


def _complete_value(token: bytes, face: bool) -> bool:
    """Whether a value is whole: a number, or a face corner ``a``, ``a/b``, ``a//c``, ``a/b/c``."""
    if not face:
        try:
            float(token)
        except ValueError:
            return False
        return True
    parts = token.split(b"/")
    return bool(parts[0]) and bool(parts[-1]) and all(not x or x.lstrip(b"-").isdigit() for x in parts)


def _cut_record(line: bytes) -> str | None:
    """Why a last line is an incomplete record, or None when it is complete or not a record."""
    tokens = line.split(b"#", 1)[0].split()
    if not tokens or tokens[0] not in _MIN_VALUES:
        return None
    key, values = tokens[0], tokens[1:]
    kind, noun = ("face", "corners") if key == b"f" else (f"'{key.decode()}'", "numbers")
    if len(values) < _MIN_VALUES[key]:
        return f"its last line, a {kind} line, holds {len(values)} of at least {_MIN_VALUES[key]} {noun}"
    cut = next((v for v in values if not _complete_value(v, key == b"f")), None)
    if cut is not None:
        return f"its last line, a {kind} line, ends in the incomplete value '{shown(cut.decode('latin-1'), 20)}'"
    return None


def check_obj_text(data: bytes, label: str) -> None:
    """Detect an OBJ file cut short (an interrupted download or copy).

    A file that does not end with a newline and whose last line is an incomplete record (a face
    with fewer than 3 corners, a vertex with fewer than 3 numbers, a value cut inside) raises
    :class:`~.normalize.MeshRejected`. When that last line is a complete record the file is
    imported, with a warning naming ``label`` that it may be cut. A file cut exactly at a line
    break cannot be told from an intact one (most valid models are open meshes), so it is
    imported as it is.
    """
    if not data or data.endswith(b"\n"):
        return
    last = data.rsplit(b"\n", 1)[-1].rstrip(b"\r")
    reason = _cut_record(last)
    if reason is not None:
        raise MeshRejected(f"file ends without a newline and {reason}: truncated file")
    tokens = last.split(b"#", 1)[0].split()
    if tokens and tokens[0] in _MIN_VALUES:
        log.warning("%s: the OBJ file does not end with a newline, so its last line '%s' may be cut short "
                    "(truncated file?); imported as it is", shown(label, 400), shown(last.decode("latin-1"), 60))


def parse_mtl(data: bytes) -> dict[str, ObjMaterial]:
    """Materials of an MTL file: diffuse colour ``Kd`` and texture ``map_Kd`` per ``newmtl``."""
    out: dict[str, ObjMaterial] = {}
    name = None
    kd: np.ndarray | None = None
    texture: str | None = None

    def flush() -> None:
        if name is not None:
            out[name] = ObjMaterial(kd=kd, texture=texture)

    for raw in data.decode("latin-1").splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        key, _, rest = line.partition(" ")
        rest = rest.strip()
        if key == "newmtl":
            flush()
            name, kd, texture = rest, None, None
        elif key == "Kd":
            try:
                vals = [float(x) for x in rest.split()[:3]]
            except ValueError:
                continue
            if len(vals) == 3 and all(np.isfinite(vals)):
                kd = np.clip(np.array(vals) * 255.0, 0, 255)
        elif key == "map_Kd" and rest:
            texture = rest.split()[-1] if rest.startswith("-") else rest
    flush()
    return out


def face_colors(obj: ObjData, materials: dict[str, ObjMaterial],
                load_texture: Callable[[str], np.ndarray | None]) -> np.ndarray:
    """(F, 3) uint8 colour per face: texture at the UV centroid (tinted by a non-white Kd), else
    the texture's mean, else Kd, else neutral grey. ``load_texture(name)`` gives an (h, w, 3)
    array or None; it is called once per texture."""
    out = np.tile(NEUTRAL_GREY.astype(np.float64), (len(obj.faces), 1))
    cache: dict[str, np.ndarray | None] = {}
    for m, name in enumerate(obj.material_names):
        mat = materials.get(name)
        if mat is None:
            continue
        sel = np.nonzero(obj.face_material == m)[0]
        if len(sel) == 0:
            continue
        tex = None
        if mat.texture:
            if mat.texture not in cache:
                cache[mat.texture] = load_texture(mat.texture)
            tex = cache[mat.texture]
        if tex is not None:
            fuv = obj.face_uv[sel]
            has_uv = (fuv >= 0).all(axis=1)
            colours = np.tile(tex.reshape(-1, 3).mean(0), (len(sel), 1))
            if has_uv.any():
                centroid = obj.uv[fuv[has_uv]].mean(axis=1)
                colours[has_uv] = sample_texture(tex, centroid)
            if mat.kd is not None and mat.kd.min() < 250:
                colours = colours * (mat.kd / 255.0)
            out[sel] = colours
        elif mat.kd is not None:
            out[sel] = mat.kd
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def obj_arrays(data: bytes, get: Callable[[str], bytes]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices (V, 3) float64, faces (F, 3) int64 and face colours (F, 3) uint8 of OBJ bytes.

    ``get(name)`` returns the bytes of a file the OBJ names (MTL, textures), relative to the OBJ's
    folder, or raises (KeyError, OSError, ValueError) when it is missing or not allowed; missing
    material files and unreadable textures fall back to grey / ``Kd``. Raises
    :class:`ObjUnsupported` when the caller should use a complete loader instead (including a
    file without faces, so that loader can say what it holds).
    """
    obj = parse_obj(data)
    if len(obj.faces) == 0:
        raise ObjUnsupported("no faces (maybe only lines or points)")
    materials: dict[str, ObjMaterial] = {}
    for lib in obj.mtllibs:
        for name in [lib] + (lib.split() if " " in lib else []):
            try:
                found = parse_mtl(get(name))
            except (KeyError, OSError, ValueError, zipfile.BadZipFile):
                continue
            folder = posixpath.dirname(name.replace("\\", "/"))
            for key, mat in found.items():
                if mat.texture and folder:
                    mat = ObjMaterial(kd=mat.kd, texture=posixpath.join(folder, mat.texture))
                materials.setdefault(key, mat)
            break

    def load_texture(name: str) -> np.ndarray | None:
        from PIL import Image

        try:
            return image_array(Image.open(io.BytesIO(get(name))))
        except Exception:  # missing, refused or undecodable image: the material colour is used instead
            log.debug("texture %r unreadable", name)
            return None

    return obj.vertices, obj.faces, face_colors(obj, materials, load_texture)
