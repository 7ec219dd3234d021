"""Exception hierarchy. Messages name the value, the expected form and a fix."""


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
        from rich.markup import escape

        result = escape(result)
    return result
