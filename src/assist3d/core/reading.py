"""The one reading layer for files that come from users: every command reads its inputs here.

Each reader turns any failure (a missing file, a folder or device where a file is expected, bytes
that are not text in the expected encoding, malformed or over-nested YAML / JSON, a truncated or
forged array, a checkpoint holding other objects than tensors, ...) into the project's own error
(``error=``, default :class:`DataError`) with one line ``"PATH: problem"``. Sizes are checked
against documented bounds *before* the work starts:

=====================  ===========================================================================
YAML (configs)         at most :data:`MAX_YAML_BYTES` bytes, :data:`MAX_DEPTH` levels of nesting and
                       :data:`MAX_YAML_NODES` values once aliases are expanded (a "billion laughs"
                       file is refused from its event stream, before any object is built)
JSON                   at most :data:`MAX_JSON_BYTES` bytes and :data:`MAX_DEPTH` levels
text (tables, lists)   at most :data:`MAX_TEXT_BYTES` bytes
``.npy`` / ``.npz``    the header's shape must fit in the file (or, compressed, in the member's
                       stated size) and in :data:`MAX_ARRAY_BYTES`; object arrays are never read
meshes                 element counts of PLY / OFF / binary STL headers must fit in the file, and
                       at most :data:`MAX_MESH_TRIANGLES` triangles / :data:`MAX_MESH_VERTICES`
                       vertices
checkpoints            PyTorch archives read with ``weights_only=True`` (tensors, numbers, text)
=====================  ===========================================================================

Nothing here runs code from data: no pickles, ``yaml.safe_load`` only, ``allow_pickle=False``.
"""

from __future__ import annotations

import json
import math
import os
import pickle
import re
import stat
import struct
import tokenize
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .errors import AssistError, DataError, shown

__all__ = [
    "MAX_TEXT_BYTES", "MAX_YAML_BYTES", "MAX_JSON_BYTES", "MAX_DEPTH", "MAX_YAML_NODES", "MAX_ARRAY_BYTES",
    "MAX_MESH_TRIANGLES", "MAX_MESH_VERTICES", "read_bytes", "read_text", "decode_text", "problem", "read_json",
    "parse_json", "read_yaml", "parse_yaml", "read_npy", "read_npz", "read_checkpoint", "check_mesh_counts",
    "check_nesting",
]

#: Largest text file read whole (label tables, benchmark prediction lists, mask files, manifests).
MAX_TEXT_BYTES = 1 << 30
#: Largest YAML file (configs are a few kB, and YAML values are built in pure Python).
MAX_YAML_BYTES = 4 << 20
#: Largest JSON file (a catalog index of the largest import stays far below it).
MAX_JSON_BYTES = 1 << 30
#: Deepest nesting of YAML / JSON (the project's own files nest fewer than 10 levels).
MAX_DEPTH = 100
#: Most values a YAML file may hold once its aliases are expanded.
MAX_YAML_NODES = 1_000_000
#: Largest array read from one ``.npy`` file or ``.npz`` member (memory-mapped reads aside).
MAX_ARRAY_BYTES = 16 << 30
#: Most triangles / vertices of one mesh (far above a scanned room or an asset).
MAX_MESH_TRIANGLES = 50_000_000
MAX_MESH_VERTICES = 50_000_000


def _where(path: str | os.PathLike) -> str:
    return shown(os.fspath(path), 400)


def problem(err: AssistError, path: str | os.PathLike) -> str:
    """The problem part of a reader's ``"PATH: problem"`` message (to put it in a longer line)."""
    text, prefix = str(err), f"{_where(path)}: "
    return text[len(prefix):] if text.startswith(prefix) else text


# ------------------------------------------------------------------------------------------------
# Bytes and text


def _check_file(path: Path, error: type[AssistError], missing: str | None) -> os.stat_result:
    try:
        st = path.stat()
    except FileNotFoundError:
        raise error(f"{_where(path)}: {missing or 'file not found'}") from None
    except OSError as e:
        raise error(f"{_where(path)}: cannot read ({shown(e.strerror or e)})") from None
    if stat.S_ISDIR(st.st_mode):
        raise error(f"{_where(path)}: is a folder, expected a file")
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{_where(path)}: is not a regular file (a device, pipe or socket); give a file path")
    return st


def _check_size(path: Path, size: int, limit: int | None, what: str, error: type[AssistError]) -> None:
    if limit is not None and size > limit:
        raise error(f"{_where(path)}: {size:,} bytes, more than the {limit:,} bytes a {what} may have; "
                    "is it the right file?")


def read_bytes(path: str | os.PathLike, *, error: type[AssistError] = DataError, limit: int | None = None,
               what: str = "file", missing: str | None = None) -> bytes:
    """The bytes of regular file ``path`` (at most ``limit`` bytes, checked from its size first).
    ``missing`` replaces ``"file not found"`` in the message for an absent file."""
    p = Path(path)
    st = _check_file(p, error, missing)
    _check_size(p, st.st_size, limit, what, error)
    try:
        with open(p, "rb") as f:
            data = f.read() if limit is None else f.read(limit + 1)
    except OSError as e:
        raise error(f"{_where(p)}: cannot read ({shown(e.strerror or e)})") from None
    _check_size(p, len(data), limit, what, error)  # it grew since stat
    return data


def decode_text(data: bytes, source: str | os.PathLike, *, error: type[AssistError] = DataError,
                what: str = "text", encoding: str = "utf-8") -> str:
    """``data`` decoded (a UTF-8 byte-order mark is dropped); an error naming ``source``, the first
    bad byte and its offset when it is not text in ``encoding``. NUL bytes are refused too (a
    binary file given by mistake)."""
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError as e:
        bad = e.object[e.start:e.start + 1]
        hint = ""
        if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
            hint = " (it looks like UTF-16)"
        raise error(f"{_where(source)}: not {encoding.upper()} text: byte {e.start} is {bad!r}{hint}; "
                    f"save the {what} as {encoding.upper()}") from None
    if text.startswith("\ufeff"):
        text = text[1:]
    nul = text.find("\0")
    if nul >= 0:
        raise error(f"{_where(source)}: not {encoding.upper()} text: a NUL byte at character {nul} (a binary file, "
                    f"or text saved as UTF-16 / UTF-32?); save the {what} as {encoding.upper()}")
    return text


def read_text(path: str | os.PathLike, *, error: type[AssistError] = DataError, limit: int | None = MAX_TEXT_BYTES,
              what: str = "text", missing: str | None = None, encoding: str = "utf-8") -> str:
    """Text file ``path`` decoded as ``encoding`` (see :func:`decode_text`)."""
    return decode_text(read_bytes(path, error=error, limit=limit, what=what, missing=missing), path, error=error,
                       what=what, encoding=encoding)


# ------------------------------------------------------------------------------------------------
# Structured text


def check_nesting(value: Any, source: str | os.PathLike, *, error: type[AssistError] = DataError,
                  depth: int = MAX_DEPTH, what: str = "file") -> Any:
    """``value`` unchanged if its lists and dicts nest at most ``depth`` levels (iterative walk)."""
    stack = [(value, 1)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, dict):
            items = v.values()
        elif isinstance(v, list):
            items = v
        else:
            continue
        if d > depth:
            raise error(f"{_where(source)}: nested too deeply (more than {depth} levels); not a valid {what}")
        stack.extend((x, d + 1) for x in items if isinstance(x, (dict, list)))
    return value


def parse_json(text: str | bytes, source: str | os.PathLike, *, error: type[AssistError] = DataError,
               depth: int = MAX_DEPTH, what: str = "JSON file") -> Any:
    """JSON ``text`` (from ``source``) parsed; malformed or too deeply nested JSON is ``error``."""
    try:
        value = json.loads(text)
    except json.JSONDecodeError as e:
        raise error(f"{_where(source)}: bad JSON at line {e.lineno} column {e.colno}: {e.msg}") from None
    except RecursionError:
        raise error(f"{_where(source)}: nested too deeply (more than {depth} levels); not a valid {what}") from None
    except (UnicodeDecodeError, ValueError) as e:  # bytes in another encoding; numbers past the int limit
        raise error(f"{_where(source)}: not valid JSON ({shown(e, 160)})") from None
    return check_nesting(value, source, error=error, depth=depth, what=what)


def read_json(path: str | os.PathLike, *, error: type[AssistError] = DataError, limit: int = MAX_JSON_BYTES,
              depth: int = MAX_DEPTH, what: str = "JSON file", missing: str | None = None) -> Any:
    """The JSON value in file ``path`` (UTF-8, a byte-order mark allowed), within the size and depth bounds."""
    text = read_text(path, error=error, limit=limit, what=what, missing=missing)
    return parse_json(text, path, error=error, depth=depth, what=what)


_SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def _yaml_bounds(text: str, source: str | os.PathLike, error: type[AssistError], depth: int, nodes: int,
                 what: str) -> None:
    """Refuse from the event stream (no objects built): nesting beyond ``depth``, or more than
    ``nodes`` values once aliases are expanded."""
    sizes: dict[str, int] = {}
    stack: list[tuple[str | None, int]] = []  # (anchor, values counted before the collection began)
    count = 0
    for ev in yaml.parse(text, Loader=_SAFE_LOADER):
        if isinstance(ev, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            stack.append((ev.anchor, count))
            count += 1
            if len(stack) > depth:
                raise error(f"{_where(source)}: nested too deeply (more than {depth} levels); not a valid {what}")
        elif isinstance(ev, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            anchor, before = stack.pop()
            if anchor is not None:
                sizes[anchor] = count - before
        elif isinstance(ev, yaml.ScalarEvent):
            count += 1
            if ev.anchor is not None:
                sizes[ev.anchor] = 1
        elif isinstance(ev, yaml.AliasEvent):
            if ev.anchor not in sizes:
                raise error(f"{_where(source)}: alias *{shown(ev.anchor, 40)} refers to a value that holds it "
                            f"(a cycle); not a valid {what}")
            count += sizes[ev.anchor]
        if count > nodes:
            raise error(f"{_where(source)}: holds more than {nodes:,} values once its aliases (*name) are "
                        f"expanded; not a valid {what}")


def parse_yaml(text: str, source: str | os.PathLike, *, error: type[AssistError] = DataError,
               depth: int = MAX_DEPTH, nodes: int = MAX_YAML_NODES, what: str = "YAML file") -> Any:
    """YAML ``text`` (from ``source``) loaded with ``yaml.safe_load`` after the depth and alias
    bounds are checked on its event stream; any failure is ``error``."""
    try:
        _yaml_bounds(text, source, error, depth, nodes, what)
        return yaml.safe_load(text)
    except yaml.YAMLError as e:
        if "maximum nesting depth" in str(e):  # libyaml's own limit (1000 flow levels)
            raise error(f"{_where(source)}: nested too deeply (more than {depth} levels); not a valid {what}") from None
        raise error(f"{_where(source)}: not valid YAML ({shown(e, 300)})") from None
    except RecursionError:
        raise error(f"{_where(source)}: nested too deeply (more than {depth} levels); not a valid {what}") from None
    except (ValueError, OverflowError, TypeError) as e:  # e.g. a timestamp or number past its range
        raise error(f"{_where(source)}: not valid YAML ({type(e).__name__}: {shown(e, 160)})") from None


def read_yaml(path: str | os.PathLike, *, error: type[AssistError] = DataError, limit: int = MAX_YAML_BYTES,
              depth: int = MAX_DEPTH, nodes: int = MAX_YAML_NODES, what: str = "YAML file",
              missing: str | None = None) -> Any:
    """The value in YAML file ``path`` (UTF-8), within the size, depth and alias bounds."""
    text = read_text(path, error=error, limit=limit, what=what, missing=missing)
    return parse_yaml(text, path, error=error, depth=depth, nodes=nodes, what=what)


# ------------------------------------------------------------------------------------------------
# Arrays


def _npy_header(f, source: str, error: type[AssistError], member: str = "") -> tuple[tuple, np.dtype, bool]:
    fmt = np.lib.format
    try:
        version = fmt.read_magic(f)
        if version == (1, 0):
            shape, fortran, dtype = fmt.read_array_header_1_0(f, max_header_size=1 << 16)
        elif version in ((2, 0), (3, 0)):
            shape, fortran, dtype = fmt.read_array_header_2_0(f, max_header_size=1 << 16)
        else:  # pragma: no cover - read_magic refuses other versions
            raise ValueError(f"unknown .npy version {version}")
    except (ValueError, OSError, EOFError, SyntaxError, TypeError, KeyError, tokenize.TokenError) as e:
        # (numpy parses the header's dict literal with the tokenizer: a damaged one raises any of these)
        raise error(f"{source}: {member}not a readable .npy array ({type(e).__name__}: {shown(e, 160)})") from None
    if dtype.hasobject:
        raise error(f"{source}: {member}.npy of Python objects (dtype {dtype}); only plain numeric arrays are read, "
                    "never pickles")
    return shape, dtype, fortran


def _array_need(source: str, shape: tuple, dtype: np.dtype, error: type[AssistError], member: str = "") -> int:
    need = math.prod(shape) * dtype.itemsize
    if need > MAX_ARRAY_BYTES:
        raise error(f"{source}: {member}array of shape {shape} and dtype {dtype} needs {need:,} bytes, more than the "
                    f"{MAX_ARRAY_BYTES:,} one array may have")
    return need


def read_npy(path: str | os.PathLike, *, error: type[AssistError] = DataError, mmap: bool = False) -> np.ndarray:
    """A ``.npy`` array without pickles. The header is checked first: object arrays are refused, and so
    is a file shorter than its header's shape says (truncated, or a forged shape that would allocate
    terabytes) or longer (a damaged or concatenated file)."""
    p = Path(path)
    st = _check_file(p, error, None)
    src = _where(p)
    try:
        with open(p, "rb") as f:
            shape, dtype, _ = _npy_header(f, src, error)
            offset = f.tell()
    except OSError as e:
        raise error(f"{src}: cannot read ({shown(e.strerror or e)})") from None
    need = math.prod(shape) * dtype.itemsize
    have = st.st_size - offset
    if need > have:
        raise error(f"{src}: truncated .npy: shape {shape} of {dtype} needs {need} bytes of data, the file holds {have}")
    if need < have:  # np.save writes exactly the array: more is a damaged or concatenated file
        raise error(f"{src}: damaged .npy: shape {shape} of {dtype} is {need} bytes of data, the file holds {have} "
                    f"({have - need} more)")
    if not mmap:
        _array_need(src, shape, dtype, error)
    try:
        return np.load(p, allow_pickle=False, mmap_mode="r" if mmap else None)
    except (ValueError, OSError, EOFError) as e:
        raise error(f"{src}: cannot load .npy ({shown(e, 160)})") from None
    except MemoryError:
        raise error(f"{src}: .npy array too large to load into memory") from None


def read_npz(path: str | os.PathLike, *, error: type[AssistError] = DataError, keys: tuple[str, ...] | None = None,
             what: str = ".npz archive", missing: str | None = None) -> dict[str, np.ndarray]:
    """The arrays of a ``.npz`` archive (only ``keys`` if given, each required), without pickles. Each
    member's header is checked against its stated size and :data:`MAX_ARRAY_BYTES` before it is
    decompressed."""
    p = Path(path)
    _check_file(p, error, missing)
    src = _where(p)
    out: dict[str, np.ndarray] = {}
    try:
        with zipfile.ZipFile(p) as z:
            members = {n[:-4] if n.endswith(".npy") else n: n for n in z.namelist()}
            want = keys if keys is not None else tuple(members)
            absent = [k for k in want if k not in members]
            if absent:
                raise error(f"{src}: {what} lacks {', '.join(repr(k) for k in absent)} (holds "
                            f"{shown(sorted(members), 160)})")
            for k in want:
                info = z.getinfo(members[k])
                with z.open(info) as f:
                    member = f"member {shown(k, 60)!r}: "
                    shape, dtype, fortran = _npy_header(f, src, error, member)
                    need = _array_need(src, shape, dtype, error, member)
                    room = info.file_size - f.tell()
                    if need > room:
                        raise error(f"{src}: member {shown(k, 60)!r} is truncated: shape {shape} of {dtype} needs "
                                    f"{need} bytes, it holds {room}")
                    data = bytearray(need)
                    got = f.readinto(data) if need else 0
                if got != need:
                    raise error(f"{src}: member {shown(k, 60)!r} is truncated")
                a = np.frombuffer(data, dtype=dtype)
                out[k] = a.reshape(shape[::-1]).T if fortran else a.reshape(shape)
    except AssistError:
        raise
    except (zlib.error, struct.error):  # a corrupt compressed member, or a member header cut short
        raise error(f"{src}: not a readable {what} (corrupt compressed data)") from None
    except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, EOFError, ValueError, RuntimeError) as e:
        # RuntimeError covers an encrypted member and an unsupported compression method
        raise error(f"{src}: not a readable {what} ({type(e).__name__}: {shown(e, 160)})") from None
    return out


# ------------------------------------------------------------------------------------------------
# Checkpoints


def read_checkpoint(path: str | os.PathLike, *, error: type[AssistError] = DataError,
                    map_location: str = "cpu") -> Any:
    """The object in PyTorch archive ``path``, loaded with ``weights_only=True``: a file holding any
    other object than tensors, numbers, text and containers is refused and runs nothing."""
    import torch  # an optional extra: only checkpoint readers need it

    p = Path(path)
    _check_file(p, error, "checkpoint not found")
    src = _where(p)
    if not zipfile.is_zipfile(p):
        raise error(f"{src}: not a readable checkpoint (not a PyTorch archive)")
    try:
        return torch.load(p, map_location=map_location, weights_only=True)
    except pickle.UnpicklingError as e:
        found = re.search(r"Unsupported global: GLOBAL ([\w.]+)", str(e))
        if found or "Unsupported" in str(e):
            name = f": {found.group(1)}" if found else ""
            raise error(f"{src}: refused: the file holds objects other than tensors and numbers{name}; "
                        "loading it could run code") from None
        raise error(f"{src}: not a readable checkpoint (UnpicklingError)") from None
    except MemoryError:
        raise error(f"{src}: checkpoint too large to load into memory") from None
    except Exception as e:  # noqa: BLE001 - torch raises many types for corrupt archives
        raise error(f"{src}: not a readable checkpoint ({type(e).__name__})") from None


# ------------------------------------------------------------------------------------------------
# Meshes: counts stated in a header must fit in the file and in the bounds


_PLY_SIZES = {"char": 1, "int8": 1, "uchar": 1, "uint8": 1, "short": 2, "int16": 2, "ushort": 2, "uint16": 2,
              "int": 4, "int32": 4, "uint": 4, "uint32": 4, "float": 4, "float32": 4, "double": 8, "float64": 8}


def _tokens(data: bytes) -> int:
    """How many whitespace-separated words ``data`` holds (counted without splitting it)."""
    if not data:
        return 0
    space = np.frombuffer(data, np.uint8) <= 32
    return int(np.count_nonzero(space[:-1] & ~space[1:])) + int(not space[0])


def _mesh_bounds(source: str, vertices: int, triangles: int, error: type[AssistError]) -> None:
    if vertices > MAX_MESH_VERTICES:
        raise error(f"{source}: {vertices:,} vertices, more than the {MAX_MESH_VERTICES:,} a mesh may have")
    if triangles > MAX_MESH_TRIANGLES:
        raise error(f"{source}: {triangles:,} faces, more than the {MAX_MESH_TRIANGLES:,} a mesh may have")


def _ply_counts(data: bytes, source: str, error: type[AssistError]) -> None:
    end = data.find(b"end_header", 0, 1 << 16)
    if end < 0:
        return  # the reader says what is wrong
    nl = data.find(b"\n", end)
    body = len(data) - (nl + 1 if nl >= 0 else len(data))
    binary = b"binary" in data[:end]
    least = values = 0
    counts: dict[str, int] = {}
    name, count, rec, props = None, 0, 0, 0
    lines = data[:end].decode("ascii", "replace").splitlines()
    for line in lines + ["element __end__ 0"]:
        tok = line.split()
        if len(tok) >= 3 and tok[0] == "element":
            if name is not None:
                counts[name] = count
                least += count * (max(rec, 1) if binary else 2 * max(props, 1))  # ascii: "v " per value
                values += count * props
            try:
                name, count, rec, props = tok[1], int(tok[2]), 0, 0
            except ValueError:
                return  # the reader names the malformed line
            if count < 0:
                raise error(f"{source}: PLY element {shown(tok[1], 40)!r} has a negative count ({count})")
        elif len(tok) >= 3 and tok[0] == "property" and name is not None:
            props += 1
            if tok[1] == "list" and len(tok) >= 5:
                rec += _PLY_SIZES.get(tok[2], 1)  # at least the list's length
            else:
                rec += _PLY_SIZES.get(tok[1], 1)
    shown_counts = ", ".join(f"{k} {v:,}" for k, v in counts.items())
    if least > body:
        raise error(f"{source}: truncated PLY: its header claims {shown_counts}: at least {least:,} bytes of data, "
                    f"the file holds {body:,}")
    if not binary:  # one line per element, one value per property at least (a list: its length)
        text = data[len(data) - body:]
        lines = sum(1 for ln in text.splitlines() if ln.strip())
        have = _tokens(text)
        records = sum(counts.values())
        if records > lines or values > have:
            raise error(f"{source}: truncated PLY: its header claims {shown_counts} ({records:,} lines, at least "
                        f"{values:,} values), the file holds {lines:,} lines and {have:,} values")
    _mesh_bounds(source, counts.get("vertex", 0), counts.get("face", 0), error)


def _off_counts(data: bytes, source: str, error: type[AssistError]) -> None:
    words: list[bytes] = []
    for line in data[:1 << 16].splitlines():
        line = line.split(b"#", 1)[0].strip()
        if line:
            words += line.split()
        if len(words) >= 4:
            break
    if not words or not words[0].endswith(b"OFF"):
        return
    nums = words[1:4]  # OFF, COFF, NOFF, ...: the vertex, face and edge counts follow the keyword
    try:
        v, f = int(nums[0]), int(nums[1])
    except (ValueError, IndexError):
        return
    if v < 0 or f < 0:
        raise error(f"{source}: OFF header has a negative count ({v} vertices, {f} faces)")
    least = 6 * v + 8 * f  # "x y z\n" and "3 a b c\n" at their shortest
    if least > len(data):
        raise error(f"{source}: OFF header claims {v:,} vertices and {f:,} faces: at least {least:,} bytes, "
                    f"the file holds {len(data):,}")
    body = b"\n".join(line.split(b"#", 1)[0] for line in data.splitlines())
    have = _tokens(body) - 4  # the keyword and the three counts
    if 3 * v + 4 * f > have:
        raise error(f"{source}: truncated OFF: its header claims {v:,} vertices and {f:,} faces (at least "
                    f"{3 * v + 4 * f:,} values), the file holds {max(have, 0):,}")
    _mesh_bounds(source, v, f, error)


def _stl_counts(data: bytes, source: str, error: type[AssistError]) -> None:
    if len(data) < 84 or data[:5].lower() == b"solid" and b"facet" in data[:1024]:
        return  # ASCII STL: its size bounds its triangles
    n = int.from_bytes(data[80:84], "little")
    if 84 + 50 * n > len(data):
        raise error(f"{source}: binary STL header claims {n:,} triangles: {84 + 50 * n:,} bytes, the file holds "
                    f"{len(data):,}")
    _mesh_bounds(source, 0, n, error)


def check_mesh_counts(data: bytes, file_type: str, source: str | os.PathLike, *,
                      error: type[AssistError] = DataError) -> None:
    """Refuse mesh bytes whose header claims more elements than the file can hold, or more than
    :data:`MAX_MESH_VERTICES` / :data:`MAX_MESH_TRIANGLES` (before a loader allocates for them).
    ``file_type``: ``ply``, ``off``, ``stl``, ``gltf`` (its JSON: size and depth; other formats: their
    size bounds their counts). A text
    format (``obj``, ``off``) holding NUL bytes (saved as UTF-16 / UTF-32) is refused too."""
    src = _where(source)
    kind = file_type.lower().lstrip(".")
    if kind in ("obj", "off") and b"\0" in data[:1 << 16]:
        raise error(f"{src}: a text mesh ({kind.upper()}) holding NUL bytes: is it saved as UTF-16 or UTF-32? "
                    "save it as UTF-8 or ASCII")
    if kind == "gltf":  # its JSON within the size and depth bounds (the buffers are separate files)
        _check_size(Path(os.fspath(source)), len(data), MAX_JSON_BYTES, "glTF file", error)
        parse_json(data, source, error=error, what="glTF file")
    elif kind == "ply":
        _ply_counts(data, src, error)
    elif kind == "off":
        _off_counts(data, src, error)
    elif kind == "stl":
        _stl_counts(data, src, error)
