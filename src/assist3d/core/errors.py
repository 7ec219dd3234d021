"""Exception hierarchy. Messages name the value, the expected form and a fix."""

import errno
import os

from rich.markup import escape


class AssistError(Exception):
    """Base class of every error assist3d raises on purpose."""


class ConfigError(AssistError):
    """A configuration value or command-line option is invalid."""


class AssetError(AssistError):
    """An asset file or catalog is missing, corrupt or unusable."""


class PlacementError(AssistError):
    """A layout search could not satisfy a request."""


class DataError(AssistError):
    """A dataset file is missing, truncated or malformed."""


class RenderError(AssistError):
    """Ray casting or fusion failed."""


class LLMError(AssistError):
    """An LLM endpoint failed or answered something unusable."""


# ------------------------------------------------------------------------------------------------
# Showing text that came from outside (LLM answers, file names, file contents)

#: Characters that are never shown raw: format controls that reorder or hide text (bidi overrides
#: and isolates, zero-width marks) and the Unicode line and paragraph separators.
_INVISIBLE = frozenset("\u200b\u200c\u200d\u200e\u200f\u202a\u202b\u202c\u202d\u202e"
                       "\u2028\u2029\u2066\u2067\u2068\u2069\ufeff")
_NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def _is_control(ch: str, keep: str) -> bool:
    o = ord(ch)
    if ch in keep:
        return False
    return o < 0x20 or 0x7F <= o <= 0x9F or ch in _INVISIBLE


def _escaped(ch: str) -> str:
    o = ord(ch)
    return _NAMED.get(ch) or (f"\\x{o:02x}" if o <= 0xFF else f"\\u{o:04x}")


def inert(text: object, *, keep: str = "") -> str:
    """``text`` with every C0/C1 control character (ESC, CR, BEL, CSI ``\\x9b``, ...), DEL and
    invisible bidi/format character written as a visible escape (``\\x1b``, ``\\r``, ``\\u202e``).
    ``keep``: characters left as they are (e.g. ``"\\n"`` for a multi-line message of our own)."""
    s = str(text)
    if not any(_is_control(ch, keep) for ch in s):
        return s
    return "".join(_escaped(ch) if _is_control(ch, keep) else ch for ch in s)


def shown(text: object, limit: int = 200, *, markup: bool = False) -> str:
    """Outside text made safe to show on one line: controls escaped (see :func:`inert`), cut to
    ``limit`` characters with ``"… (N more chars)"`` (N counts the characters of ``text`` left out).
    ``markup=True`` also escapes rich markup (``[bold]``) for a console that interprets it."""
    s = str(text)
    out: list[str] = []
    used = 0
    for i, ch in enumerate(s):
        piece = _escaped(ch) if _is_control(ch, "") else ch
        if used + len(piece) > limit:
            out.append(f"… ({len(s) - i} more chars)")
            break
        out.append(piece)
        used += len(piece)
    result = "".join(out)
    if markup:
        result = escape(result)
    return result


# ------------------------------------------------------------------------------------------------
# Faults of the machine (disk full, read-only, permissions, a file where a folder is expected)


class FaultError(AssistError):
    """The operating system refused a read or a write; the message names the path and a way on."""


#: errno -> (what happened, what to do)
_FAULTS: dict[int, tuple[str, str]] = {
    errno.ENOSPC: ("no space left on the device", "free some space or choose another folder"),
    errno.EDQUOT: ("disk quota exceeded", "free some space or choose another folder"),
    errno.EFBIG: ("file too large for this file system", "choose a folder on another file system"),
    errno.EROFS: ("read-only file system", "choose a writable folder"),
    errno.EACCES: ("permission denied", "check the permissions or choose another folder"),
    errno.EPERM: ("operation not permitted", "check the permissions or choose another folder"),
    errno.EISDIR: ("is a folder, expected a file", "give a file path"),
    errno.ENOTDIR: ("not a folder", "remove the file or choose another path"),
    errno.EEXIST: ("already exists", "remove it or choose another path"),
    errno.ENOENT: ("not found", "check the path"),
    errno.ENAMETOOLONG: ("file name too long", "choose a shorter path"),
    errno.ELOOP: ("too many levels of symbolic links", "check the links on the path"),
    errno.EMFILE: ("too many open files", "raise the limit (ulimit -n) or use fewer workers"),
    errno.ENFILE: ("too many open files in the system", "close other programs or use fewer workers"),
    errno.EIO: ("input/output error", "check the disk or network file system"),
    errno.EBUSY: ("device or resource busy", "wait a moment"),
}


def _file_on_path(path: str) -> str | None:
    """The first part of ``path`` (itself or a parent) that exists and is not a folder."""
    p = os.path.abspath(path)
    while True:
        if os.path.lexists(p) and not os.path.isdir(p):
            return p
        parent = os.path.dirname(p)
        if parent == p:
            return None
        p = parent


def _what_and_advice(err: OSError) -> tuple[str, str]:
    return _FAULTS.get(err.errno or -1, (inert(err.strerror or type(err).__name__), "check the path"))


def fault_advice(err: OSError) -> str:
    """What to do about ``err`` (``"free some space or choose another folder"``)."""
    return _what_and_advice(err)[1]


def describe_os_error(err: OSError, *, advice: bool = True) -> str:
    """One line for an :class:`OSError`: the path, what happened and (``advice``) what to do.

    ``ENOTDIR`` / ``EEXIST`` name the part of the path that is a file; ``EISDIR`` from a rename
    names the target. Paths are shown inert (see :func:`shown`)."""
    what, todo = _what_and_advice(err)
    tail = f"; {todo}" if advice else ""
    path = err.filename2 if err.errno == errno.EISDIR and err.filename2 is not None else err.filename
    if path is not None and err.errno in (errno.ENOTDIR, errno.EEXIST):
        blocker = _file_on_path(str(path))
        if blocker is not None:
            tail = "; remove the file or choose another path" if advice else ""
            return f"{shown(blocker, 400)}: is a file where a folder is expected{tail}"
    if path is None:
        return f"{what}{tail}"
    return f"{shown(path, 400)}: {what}{tail}"
