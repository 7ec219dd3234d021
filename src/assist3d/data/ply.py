"""A small PLY reader (binary little/big endian and ascii), enough for scanned meshes.

Reads the ``vertex`` element into a numpy structured array and, when asked, a triangular ``face``
element into an ``(F, 3) int64`` array. Elements are read in file order; list properties are read
with a vectorised fast path that needs every list of an element to have the same length (true for
the triangle meshes of ScanNet and ScanNet++). Every problem raises :class:`DataError` naming the
file.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core import reading
from ..core.errors import DataError, shown
from ..core.fileio import write_bytes_atomic
from .base import checked_coords, clean_colors, clean_normals

log = logging.getLogger(__name__)

_TYPES: dict[str, str] = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_MAX_HEADER_BYTES = 1 << 16


@dataclass(frozen=True)
class _Property:
    name: str
    dtype: str  # numpy type code without byte order, e.g. "f4"
    count_dtype: str | None = None  # set for list properties


@dataclass(frozen=True)
class _Element:
    name: str
    count: int
    properties: tuple[_Property, ...]

    @property
    def has_list(self) -> bool:
        return any(p.count_dtype is not None for p in self.properties)


@dataclass(frozen=True)
class PlyMesh:
    """What :func:`read_ply` returns.

    vertex: structured array, one field per vertex property (e.g. ``x, y, z, red, green, blue``);
    faces: ``(F, 3) int64`` triangle vertex indices, or ``None`` when not read or absent.
    """

    path: Path
    vertex: np.ndarray
    faces: np.ndarray | None

    def xyz(self) -> np.ndarray:
        """``(N, 3) float32`` vertex positions (as stored: not checked to be finite; doubles too
        large for float32 become inf)."""
        with np.errstate(over="ignore", invalid="ignore"):
            return _stack_fields(self, ("x", "y", "z")).astype(np.float32, copy=False)

    def rgb(self) -> np.ndarray | None:
        """``(N, 3) uint8`` vertex colours, or ``None`` when the file has none."""
        names = self.vertex.dtype.names or ()
        for fields in (("red", "green", "blue"), ("r", "g", "b"), ("diffuse_red", "diffuse_green", "diffuse_blue")):
            if all(f in names for f in fields):
                c = _stack_fields(self, fields)
                if c.dtype.kind == "f":
                    finite = c[np.isfinite(c)]
                    if finite.size and float(finite.max()) <= 1.0:
                        c = c * 255.0
                return clean_colors(self.path, c)
        return None


def mesh_normals(mesh: "PlyMesh") -> np.ndarray:
    """``(N, 3) float32`` normals: the file's ``nx, ny, nz`` if present, else area-weighted vertex
    normals from the faces, else zeros."""
    names = mesh.vertex.dtype.names or ()
    if all(f in names for f in ("nx", "ny", "nz")):
        return clean_normals(mesh.path, _stack_fields(mesh, ("nx", "ny", "nz")))
    coord = mesh.xyz()
    if mesh.faces is None:
        return np.zeros((len(coord), 3), np.float32)
    try:
        return vertex_normals(coord, mesh.faces)
    except DataError as e:
        raise DataError(f"{mesh.path}: {e}") from None


def _stack_fields(mesh: PlyMesh, fields: tuple[str, ...]) -> np.ndarray:
    names = mesh.vertex.dtype.names or ()
    missing = [f for f in fields if f not in names]
    if missing:
        raise DataError(f"{mesh.path}: PLY vertex element lacks properties {missing} (has {list(names)})")
    return np.stack([np.asarray(mesh.vertex[f]) for f in fields], axis=1)


def _parse_header(path: Path, raw: bytes) -> tuple[str, list[_Element], int]:
    end = raw.find(b"end_header")
    if not raw.startswith(b"ply") or end < 0:
        raise DataError(f"{path}: not a PLY file (no 'ply' magic or no 'end_header' in the first {_MAX_HEADER_BYTES} bytes)")
    nl = raw.find(b"\n", end)
    if nl < 0:
        raise DataError(f"{path}: truncated PLY header")
    body = nl + 1
    fmt = ""
    elements: list[_Element] = []
    props: list[_Property] = []
    name, count = "", 0
    for line_no, line in enumerate(raw[:end].decode("ascii", "replace").splitlines(), start=1):
        tok = line.split()
        if not tok or tok[0] in ("ply", "comment", "obj_info"):
            continue
        try:
            if tok[0] == "format":
                fmt = tok[1]
            elif tok[0] == "element":
                if name:
                    elements.append(_Element(name, count, tuple(props)))
                name, count, props = tok[1], int(tok[2]), []
            elif tok[0] == "property":
                if tok[1] == "list":
                    props.append(_Property(tok[4], _TYPES[tok[3]], _TYPES[tok[2]]))
                else:
                    props.append(_Property(tok[2], _TYPES[tok[1]]))
            else:
                raise DataError(f"{path}: PLY header line {line_no}: unknown keyword '{shown(tok[0])}'")
        except (IndexError, KeyError, ValueError) as e:
            raise DataError(f"{path}: PLY header line {line_no} is malformed: '{shown(line)}' ({shown(e)})") from None
    if name:
        elements.append(_Element(name, count, tuple(props)))
    if fmt not in ("binary_little_endian", "binary_big_endian", "ascii"):
        raise DataError(f"{path}: unsupported PLY format {fmt!r}")
    return fmt, elements, body


def read_ply(path: str | Path, *, faces: bool = False) -> PlyMesh:
    """Read a PLY file's vertices (and triangles when ``faces``).

    Raises :class:`DataError` for a missing file, a malformed header, truncated data, or (with
    ``faces``) non-triangular faces.
    """
    path = Path(path)
    data = reading.read_bytes(path, what="PLY file")
    fmt, elements, offset = _parse_header(path, data[:_MAX_HEADER_BYTES])
    reading.check_mesh_counts(data, "ply", path)
    if not any(e.name == "vertex" for e in elements):
        raise DataError(f"{path}: PLY file has no 'vertex' element")
    if fmt == "ascii":
        return _read_ascii(path, data[offset:], elements, faces)
    order = "<" if fmt == "binary_little_endian" else ">"
    vertex: np.ndarray | None = None
    tris: np.ndarray | None = None
    for el in elements:
        if el.name == "vertex" and el.has_list:
            raise DataError(f"{path}: PLY vertex element has list properties, which are not supported")
        if not el.has_list:
            dt = np.dtype([(p.name, order + p.dtype) for p in el.properties])
            need = dt.itemsize * el.count
            if offset + need > len(data):
                raise DataError(
                    f"{path}: truncated PLY: element {el.name!r} needs {need} bytes, "
                    f"{max(0, len(data) - offset)} remain"
                )
            arr = np.frombuffer(data, dtype=dt, count=el.count, offset=offset)
            offset += need
        else:
            arr, offset = _read_binary_lists(path, data, offset, el, order)
        if el.name == "vertex":
            vertex = arr.astype(arr.dtype.newbyteorder("="))
            if not faces:
                break
        elif el.name == "face" and faces:
            tris = _faces_from(path, arr, el)
            break
    if vertex is None:
        raise DataError(f"{path}: PLY vertex element could not be read")
    return PlyMesh(path, vertex, tris)


def _read_binary_lists(path: Path, data: bytes, offset: int, el: _Element, order: str) -> tuple[np.ndarray, int]:
    """Fixed-length fast path: read the first record's list lengths, then check them all."""
    if el.count == 0:
        return np.zeros(0, dtype=[(p.name, "i8") for p in el.properties]), offset
    fields: list[tuple] = []
    pos = offset
    for p in el.properties:
        if p.count_dtype is None:
            fields.append((p.name, order + p.dtype))
            pos += np.dtype(p.dtype).itemsize
        else:
            cdt = np.dtype(order + p.count_dtype)
            if pos + cdt.itemsize > len(data):
                raise DataError(f"{path}: truncated PLY in element {el.name!r}")
            k = int(np.frombuffer(data, dtype=cdt, count=1, offset=pos)[0])
            fields.append((p.name + "__count", cdt.str))
            fields.append((p.name, order + p.dtype, (k,)))
            pos += cdt.itemsize + k * np.dtype(p.dtype).itemsize
    dt = np.dtype(fields)
    need = dt.itemsize * el.count
    if offset + need > len(data):
        raise DataError(f"{path}: truncated PLY: element {el.name!r} needs {need} bytes, {max(0, len(data) - offset)} remain")
    arr = np.frombuffer(data, dtype=dt, count=el.count, offset=offset)
    for p in el.properties:
        if p.count_dtype is not None and np.any(arr[p.name + "__count"] != arr[p.name].shape[1]):
            raise DataError(f"{path}: PLY element {el.name!r} has lists of varying length; only uniform lists are supported")
    return arr, offset + need


def _faces_from(path: Path, arr: np.ndarray, el: _Element) -> np.ndarray:
    names = arr.dtype.names or ()
    key = "vertex_indices" if "vertex_indices" in names else ("vertex_index" if "vertex_index" in names else None)
    if key is None:
        raise DataError(f"{path}: PLY face element has no vertex_indices list")
    f = np.asarray(arr[key]).astype(np.int64)
    if f.ndim != 2 or (len(f) and f.shape[1] != 3):
        raise DataError(f"{path}: PLY faces are not triangles (shape {f.shape})")
    return f.reshape(-1, 3)


def _read_ascii(path: Path, body: bytes, elements: list[_Element], faces: bool) -> PlyMesh:
    lines = body.split(b"\n")
    row = 0
    vertex: np.ndarray | None = None
    tris: np.ndarray | None = None
    for el in elements:
        chunk = lines[row: row + el.count]
        if len(chunk) < el.count or (el.count and not chunk[-1].strip()):
            raise DataError(f"{path}: truncated PLY: element {el.name!r} needs {el.count} lines, {len([c for c in chunk if c.strip()])} remain")
        row += el.count
        try:
            values = np.array(b" ".join(chunk).split(), dtype=np.float64)
        except ValueError as e:
            raise DataError(f"{path}: PLY element {el.name!r} holds a non-numeric value ({e})") from None
        if el.name == "vertex":
            if el.has_list:
                raise DataError(f"{path}: PLY vertex element has list properties, which are not supported")
            width = len(el.properties)
            if values.size != width * el.count:
                raise DataError(f"{path}: PLY vertex lines hold {values.size} values, expected {width} x {el.count}")
            table = values.reshape(el.count, width)
            vertex = np.zeros(el.count, dtype=[(p.name, p.dtype) for p in el.properties])
            for j, p in enumerate(el.properties):
                vertex[p.name] = table[:, j]
            if not faces:
                break
        elif el.name == "face" and faces:
            if el.count == 0:
                tris = np.zeros((0, 3), np.int64)
            elif values.size != 4 * el.count or np.any(values.reshape(-1, 4)[:, 0] != 3):
                raise DataError(f"{path}: PLY faces are not all triangles")
            else:
                tris = values.reshape(-1, 4)[:, 1:].astype(np.int64)
            break
    if vertex is None:
        raise DataError(f"{path}: PLY vertex element could not be read")
    return PlyMesh(path, vertex, tris)


def vertex_normals(coord: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals ``(N, 3) float32`` (zeros for vertices on no face)."""
    n = len(coord)
    normals = np.zeros((n, 3), np.float64)
    if len(faces) == 0:
        return normals.astype(np.float32)
    if faces.min() < 0 or faces.max() >= n:
        raise DataError(f"face indices out of range 0..{n - 1}")
    v = coord.astype(np.float64)
    fn = np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])
    for k in range(3):
        for d in range(3):
            normals[:, d] += np.bincount(faces[:, k], weights=fn[:, d], minlength=n)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    np.divide(normals, length, out=normals, where=length > 0)
    return normals.astype(np.float32)


#: PLY type names of the numpy dtypes our writers use
_PLY_TYPES = {"<f4": "float", "u1": "uchar", "<u2": "ushort", "<i4": "int"}


def binary_ply(columns: list[tuple[str, str, np.ndarray | int]], faces: np.ndarray | None = None, *,
               comment: str | None = None) -> bytes:
    """A binary little-endian PLY: one vertex property per ``(name, dtype, values)`` column in that order
    (dtype ``<f4``, ``u1``, ``<u2`` or ``<i4``; a number fills the column), and ``faces`` (F, 3) as
    ``vertex_indices`` lists when given."""
    n = len(columns[0][2])
    v = np.zeros(n, dtype=[(name, t) for name, t, _ in columns])
    for name, _, values in columns:
        v[name] = values
    header = ["ply", "format binary_little_endian 1.0", *([f"comment {comment}"] if comment else []),
              f"element vertex {n}", *(f"property {_PLY_TYPES[t]} {name}" for name, t, _ in columns)]
    body = v.tobytes()
    if faces is not None:
        header += [f"element face {len(faces)}", "property list uchar int vertex_indices"]
        f = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
        f["n"], f["i"] = 3, faces
        body += f.tobytes()
    header.append("end_header")
    return ("\n".join(header) + "\n").encode("ascii") + body


def xyz_rgba_columns(coord: np.ndarray, color: np.ndarray | None) -> list[tuple[str, str, np.ndarray | int]]:
    """The ``x y z`` and, with ``color``, ``red green blue alpha`` (255) columns of :func:`binary_ply`."""
    cols: list[tuple[str, str, np.ndarray | int]] = [("x", "<f4", coord[:, 0]), ("y", "<f4", coord[:, 1]),
                                                     ("z", "<f4", coord[:, 2])]
    if color is not None:
        cols += [("red", "u1", color[:, 0]), ("green", "u1", color[:, 1]), ("blue", "u1", color[:, 2]),
                 ("alpha", "u1", 255)]
    return cols


def write_ply(path: str | Path, coord: np.ndarray, color: np.ndarray | None = None, faces: np.ndarray | None = None,
              *, instance: np.ndarray | None = None) -> None:
    """Write a binary little-endian PLY (ScanNet's property names: x y z, red green blue alpha) and,
    with ``instance`` (N,), each vertex's instance id as an ``int instance`` property after them."""
    cols = xyz_rgba_columns(coord, color)
    if instance is not None:
        if len(instance) != len(coord):
            raise ValueError(f"instance: {len(instance)} values for {len(coord)} vertices")
        cols.append(("instance", "<i4", instance))
    write_bytes_atomic(path, binary_ply(cols, faces))


def read_scan_mesh(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A scan mesh's per-vertex (coord (n, 3) float32, color (n, 3) uint8 (zeros when the file has
    none), normal (n, 3) float32 area-weighted vertex normals), in vertex order. An empty mesh and
    non-finite or far-out coordinates raise :class:`DataError`; colours are cleaned (see
    :func:`~.base.clean_colors`)."""
    mesh = read_ply(path, faces=True)
    coord = checked_coords(mesh.path, mesh.xyz(), "vertex coordinates")
    color = mesh.rgb()
    if color is None:
        color = np.zeros((len(coord), 3), np.uint8)
    return coord, color, mesh_normals(mesh)
