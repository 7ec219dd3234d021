"""The import driver shared by the importers: convert items in a process pool, register results.

An importer supplies a list of picklable items, a module-level ``convert(item)`` returning
``(AssetRecord, MeshData)`` or a :class:`SkippedAsset`, and how to name an item's catalog part.
The driver writes each mesh (atomically) and saves the index every ``save_every`` assets and at
the end, so a killed import leaves only complete entries.
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass
from typing import Callable, Sequence, TypeVar

from ..core.contracts import AssetRecord, MeshData, SkippedAsset
from ..core.errors import shown
from ..core.interrupts import worker_pool
from .catalog import Catalog

log = logging.getLogger(__name__)

Item = TypeVar("Item")
Progress = Callable[[int, int, str], None]


@dataclass(frozen=True)
class ImportReport:
    """What an import did: asset counts per catalog part, skipped items, wall time."""

    added: dict[str, int]
    skipped: tuple[SkippedAsset, ...]
    seconds: float

    @property
    def total(self) -> int:
        return sum(self.added.values())

    def to_json(self) -> dict:
        return {"added": self.added, "total": self.total, "skipped": [s.to_json() for s in self.skipped],
                "seconds": round(self.seconds, 2)}


def worker_count(workers: int | None, jobs: int) -> int:
    """``workers`` (default: the CPU count) bounded by the number of jobs, at least 1."""
    if workers is None:
        workers = os.cpu_count() or 1
    return max(1, min(int(workers), jobs))


def run_import(catalog: Catalog, items: Sequence[Item],
               convert: Callable[[Item], tuple[AssetRecord, MeshData] | SkippedAsset], *, source: str,
               part_of: Callable[[Item], str], label_of: Callable[[Item], str], parts: Sequence[str],
               skipped: Sequence[SkippedAsset] = (), workers: int | None = None, save_every: int = 50,
               progress: Progress | None = None, started: float | None = None) -> ImportReport:
    """Convert ``items`` (in ``workers`` processes) and add the results to ``catalog``.

    ``part_of(item)`` names the catalog part the item belongs to (its ids start with
    ``f"{source}:{part}/"``); skipped items are recorded under that prefix. ``skipped`` are
    problems found before conversion (already registered by the caller). Returns the report.
    """
    t0 = time.perf_counter() if started is None else started
    added: dict[str, int] = {p: 0 for p in parts}
    all_skipped: list[SkippedAsset] = list(skipped)
    total = len(items)
    done = 0

    def handle(item: Item, result: tuple[AssetRecord, MeshData] | SkippedAsset) -> None:
        nonlocal done
        done += 1
        part = part_of(item)
        if isinstance(result, SkippedAsset):
            all_skipped.append(result)
            catalog.add_skipped(result, source, f"{source}:{part}/")
            log.info("%s: skipped %s: %s", source, shown(result.path, 400), shown(result.reason))
        else:
            record, mesh = result
            catalog.add(record, mesh)
            added[part] = added.get(part, 0) + 1
        if save_every > 0 and done % save_every == 0:
            catalog.save()
        if progress is not None:
            progress(done, total, label_of(item))

    n_workers = worker_count(workers, total)
    if n_workers <= 1 or total <= 4:
        for item in items:
            handle(item, convert(item))
    else:
        # the workers are forked (fast start); callers must not run threads that hold locks the
        # workers need (the CLI's progress bar refreshes from this thread, not its own)
        with worker_pool(n_workers) as pool:  # stopped at once on an interrupt
            for item, result in zip(items, pool.map(convert, items, chunksize=2)):
                handle(item, result)
    catalog.save()
    seconds = time.perf_counter() - t0
    log.info("%s: %d assets imported, %d skipped in %.1f s", source, sum(added.values()), len(all_skipped), seconds)
    return ImportReport(added=added, skipped=tuple(all_skipped), seconds=seconds)
