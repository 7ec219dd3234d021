"""A Java ``.properties`` reader (the format of Sweet Home 3D furniture catalogs).

Follows ``java.util.Properties.load``: ISO-8859-1 text, ``#``/``!`` comments, keys ended by the
first unescaped ``=``, ``:`` or white space, line continuations with a trailing backslash,
``\\u`` + four hex digits and ``\\t \\n \\r \\f`` escapes. A malformed line (a bad ``\\u`` escape) is reported
and skipped instead of failing the whole file.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

_WS = " \t\f"
_ESCAPES = {"t": "\t", "n": "\n", "r": "\r", "f": "\f"}
_INDEXED = re.compile(r"^(?P<key>[A-Za-z_][A-Za-z0-9_]*)#(?P<index>\d+)$")


@dataclass(frozen=True)
class Properties:
    """Parsed properties: ``values`` in file order (later duplicates win), ``errors`` one line each."""

    values: dict[str, str]
    errors: tuple[str, ...] = ()
    indexed: dict[int, dict[str, str]] = field(default_factory=dict)  # "name#3" -> {3: {"name": ...}}


def _logical_lines(text: str) -> list[tuple[int, str]]:
    """(first line number, logical line) with continuations joined; comments and blanks dropped."""
    out: list[tuple[int, str]] = []
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    i = 0
    while i < len(lines):
        start = i
        line = lines[i].lstrip(_WS)
        i += 1
        if not line or line[0] in "#!":
            continue
        parts = []
        while True:
            trailing = len(line) - len(line.rstrip("\\"))
            if trailing % 2 == 1 and i <= len(lines):
                parts.append(line[:-1])
                if i >= len(lines):
                    break
                line = lines[i].lstrip(_WS)
                i += 1
                continue
            parts.append(line)
            break
        out.append((start + 1, "".join(parts)))
    return out


def _unescape(s: str) -> str:
    """Resolve backslash escapes; raises ValueError on a malformed ``\\u`` escape."""
    if "\\" not in s:
        return s
    out = []
    i = 0
    n = len(s)
    while i < n:
        c = s[i]
        if c != "\\":
            out.append(c)
            i += 1
            continue
        if i + 1 >= n:
            i += 1
            continue
        e = s[i + 1]
        if e == "u":
            code = s[i + 2:i + 6]
            if len(code) != 4 or not all(ch in "0123456789abcdefABCDEF" for ch in code):
                raise ValueError(f"malformed \\uxxxx escape {s[i:i + 6]!r}")
            out.append(chr(int(code, 16)))
            i += 6
        else:
            out.append(_ESCAPES.get(e, e))
            i += 2
    return "".join(out)


def _split(line: str) -> tuple[str, str]:
    """Split a logical line into raw (still escaped) key and value."""
    i = 0
    n = len(line)
    while i < n:
        c = line[i]
        if c == "\\":
            i += 2
            continue
        if c in "=:" or c in _WS:
            break
        i += 1
    key = line[:i]
    j = i
    while j < n and line[j] in _WS:
        j += 1
    if j < n and line[j] in "=:":
        j += 1
        while j < n and line[j] in _WS:
            j += 1
    return key, line[j:]


def parse_properties(data: bytes | str, *, source: str = "<properties>") -> Properties:
    """Parse properties text (bytes are decoded as ISO-8859-1, as Java does).

    ``errors`` holds ``"<source>:<line>: <problem>"`` for each skipped line. ``indexed`` groups
    ``key#N`` entries by ``N``.
    """
    text = data.decode("iso-8859-1") if isinstance(data, (bytes, bytearray)) else data
    values: dict[str, str] = {}
    errors: list[str] = []
    for lineno, line in _logical_lines(text):
        raw_key, raw_value = _split(line)
        try:
            key = _unescape(raw_key)
            value = _unescape(raw_value)
        except ValueError as e:
            errors.append(f"{source}:{lineno}: {e}")
            continue
        if not key:
            errors.append(f"{source}:{lineno}: empty key")
            continue
        values[key] = value
    indexed: dict[int, dict[str, str]] = {}
    for key, value in values.items():
        m = _INDEXED.match(key)
        if m:
            indexed.setdefault(int(m.group("index")), {})[m.group("key")] = value
    return Properties(values=values, errors=tuple(errors), indexed=dict(sorted(indexed.items())))
