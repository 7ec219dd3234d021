"""Default locations. Every one is overridable by a flag and an environment variable."""

from __future__ import annotations

import os
from pathlib import Path

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
