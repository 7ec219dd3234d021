"""Default locations. Every one is overridable by a flag and an environment variable."""

from __future__ import annotations

import os
from pathlib import Path, PurePosixPath, PureWindowsPath

from .errors import AssistError, DataError, shown

ENV_ASSETS = "ASSIST3D_ASSETS"
ENV_CACHE = "ASSIST3D_CACHE"


def cache_root() -> Path:
    """``$ASSIST3D_CACHE``, else ``$XDG_CACHE_HOME/assist3d``, else ``~/.cache/assist3d``."""
    if os.environ.get(ENV_CACHE):
        return Path(os.environ[ENV_CACHE]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base).expanduser() / "assist3d"


def default_library() -> Path:
    """The asset catalog used when ``--library`` is not given.

    ``$ASSIST3D_ASSETS`` if set, else ``<cache_root>/assets``.
    """
    if os.environ.get(ENV_ASSETS):
        return Path(os.environ[ENV_ASSETS]).expanduser()
    return cache_root() / "assets"


def resolve_library(library: str | os.PathLike | None) -> Path:
    """``library`` if given, else :func:`default_library`."""
    return Path(library).expanduser() if library else default_library()


def inside(base: str | os.PathLike, relative: object, *, what: str,
           error: type[AssistError] = DataError) -> Path:
    """``base / relative``, refused unless it stays inside ``base`` once ``..`` and symlinks are
    resolved. ``relative`` comes from a file's contents (a manifest entry, a mask path, ...);
    ``what`` names where it was read (``"preds/scene0.txt: line 3"``) for the one-line error, which
    is ``error`` (default :class:`DataError`). Absolute paths (POSIX or Windows) are refused too."""
    if not isinstance(relative, (str, os.PathLike)):
        raise error(f"{what}: expected a relative path, got {type(relative).__name__}")
    text = os.fspath(relative)
    if not isinstance(text, str) or not text.strip():
        raise error(f"{what}: empty path" if isinstance(text, str) else f"{what}: expected a text path")
    if PurePosixPath(text).is_absolute() or PureWindowsPath(text).is_absolute() or PureWindowsPath(text).drive:
        raise error(f"{what}: path '{shown(text)}' is absolute; it must be relative to {shown(base)}")
    root = Path(base).resolve()
    full = (root / text).resolve()
    if not full.is_relative_to(root):
        raise error(f"{what}: path '{shown(text)}' leads outside {shown(base)} (to {shown(full)}); refused")
    return Path(base) / text


def safe_name(name: object, *, what: str, error: type[AssistError] = DataError) -> str:
    """``name`` if it can be one file or folder name (a scene id used in an output path): text, not
    empty, not ``.`` or ``..``, without ``/``, ``\\`` or NUL; else ``error``."""
    if not isinstance(name, str) or name in ("", ".", "..") or any(c in name for c in "/\\\0"):
        raise error(f"{what}: '{shown(name)}' cannot be a file name (it must be non-empty, not '.' or '..', "
                    f"without '/', '\\' or NUL)")
    return name
