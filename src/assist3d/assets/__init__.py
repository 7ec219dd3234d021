"""The asset base: catalogs of normalised meshes from real CAD collections or the procedural library.

``open_catalog`` is the one entry point the generator uses.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

from ..core.paths import ENV_ASSETS, cache_root, default_library
from .catalog import Catalog

if TYPE_CHECKING:
    from ..config import AssetsConfig

log = logging.getLogger(__name__)

__all__ = ["Catalog", "open_catalog", "open_catalog_for", "class_list", "procedural_library_dir"]


def procedural_library_dir(count: int, seed: int) -> Path:
    """Where the built-in procedural library of ``count`` assets and ``seed`` is cached."""
    return cache_root() / f"procedural-{count}-{seed}"


def open_catalog(library: str | Path | None = None, *, procedural_count: int = 2000, procedural_seed: int = 0) -> Catalog:
    """The catalog to generate from.

    ``library`` if given (it must exist); else ``$ASSIST3D_ASSETS`` / the default catalog folder
    if an import created it; else the built-in procedural library, built once and cached.
    The log says which one is used.
    """
    if library is not None:
        cat = Catalog.open(library)
        log.info("assets: catalog %s (%d assets)", library, len(cat))
        return cat
    default = default_library()
    if Catalog.exists(default):
        cat = Catalog.open(default)
        log.info("assets: default catalog %s (%d assets; set --assets or $%s to change)", default, len(cat), ENV_ASSETS)
        return cat
    root = procedural_library_dir(procedural_count, procedural_seed)
    cat = Catalog.open(root) if Catalog.exists(root) else None
    if cat is None or _stale_procedural(cat, procedural_count):
        from .procedural import build_library

        log.info("assets: %s the built-in procedural library (%d assets, seed %d) in %s",
                 "building" if cat is None else "rebuilding (made by an older version)",
                 procedural_count, procedural_seed, root)
        build_library(root, count=procedural_count, seed=procedural_seed)
        cat = Catalog.open(root)
    log.info("assets: built-in procedural library %s (%d assets)", root, len(cat))
    return cat


def open_catalog_for(assets: AssetsConfig) -> Catalog:
    """:func:`open_catalog` with the settings of a config's ``assets`` section."""
    return open_catalog(assets.library, procedural_count=assets.procedural_count,
                        procedural_seed=assets.procedural_seed)


def _stale_procedural(cat: Catalog, count: int) -> bool:
    """A cached procedural library made by another generator version (or cut short)."""
    from .procedural import GENERATOR_VERSION

    recs = cat.records
    return len(recs) != count or any(r.extra.get("version") != GENERATOR_VERSION for r in recs[:: max(1, len(recs) // 50)])


def class_list(catalog: Catalog) -> tuple[str, ...]:
    """The catalog's classes, sorted: a point's ``segment`` value indexes this list."""
    return tuple(sorted({r.class_name for r in catalog.records}))
