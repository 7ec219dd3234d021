"""Depth-first placement of planned objects: the floor, the walls and the top of each support.

``place_group`` turns one group's plan (objects in order, with relations to earlier objects)
into poses with the bounded depth-first search of :mod:`.search`; ``place_group_random`` is the
RandomRooms-style baseline. Both return a :class:`PlacementResult` with every planned object
either placed or dropped with a reason.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from ..assets.catalog import Catalog
from ..config import LayoutConfig
from ..core.contracts import DroppedObject, PlacedInstance
from ..core.errors import PlacementError
from ..planning.relations import GroupPlan, PlanRequest, group_kind
from ..core.geometry import pose_matrix
from .common import Item, relations_for_instance, resolve_plan
from .floor import FloorProblem
from .ontop import OnTopProblem
from .random import drop_randomly
from .search import depth_first
from .wall import WallProblem

log = logging.getLogger(__name__)

__all__ = ["PlacementResult", "place_group", "place_group_random", "instance_group"]

@dataclass(frozen=True)
class PlacementResult:
    """What one group's placement produced.

    ``instances`` have ids assigned consecutively from ``next_id`` in placement order;
    ``dropped`` lists every planned object not placed, with a reason; ``score`` is the mean
    soft-relation score of the placed objects (1.0 for an object without relations); ``stats``
    holds search counters (nodes, backtracks, solutions, stop, budget_hit, seconds, notes).
    """

    instances: tuple[PlacedInstance, ...]
    dropped: tuple[DroppedObject, ...]
    score: float
    seconds: float
    stats: dict = field(default_factory=dict)


def instance_group(group: str) -> str:
    """The asset group a placed instance of plan group ``group`` belongs to: floor, wall or obj."""
    kind = group_kind(group)
    return "obj" if kind == "on" else kind


def _sizes(catalog: Catalog, request: PlanRequest) -> dict[str, tuple[float, float, float]]:
    sizes: dict[str, tuple[float, float, float]] = {r.id: r.size for r in request.objects}
    for inst in request.placed + ((request.support,) if request.support else ()):
        if inst.asset not in sizes:
            sizes[inst.asset] = catalog.get(inst.asset).size
    return sizes


def _support(request: PlanRequest) -> PlacedInstance | None:
    if request.support is not None:
        return request.support
    try:
        sid = int(request.group.split(":", 1)[1])
    except (IndexError, ValueError):
        return None
    return next((p for p in request.placed if p.id == sid), None)


def _bad_size(item: Item) -> Item:
    size = item.record.size
    if len(size) == 3 and all(np.isfinite(v) and v > 0 for v in size):
        return item
    return Item(item.record, item.relations, f"invalid size {size}; expected three positive numbers")


def place_group(request: PlanRequest, plan: GroupPlan, catalog: Catalog, *, cfg: LayoutConfig,
                rng: np.random.Generator, next_id: int) -> PlacementResult:
    """Place one group ("floor", "wall" or "on:<support id>") by bounded depth-first search.

    ``request.placed`` holds every instance already in the scene (floor objects when placing the
    walls, everything when placing on top); ``request.support`` is the support of an on-top
    group. A malformed plan or an impossible object never raises: the object is dropped and the
    reason recorded. Raises :class:`PlacementError` only for an unknown group name.
    """
    t0 = time.perf_counter()
    kind = group_kind(request.group)
    if kind not in ("floor", "wall", "on"):
        raise PlacementError(f"unknown group {request.group!r}; expected 'floor', 'wall' or 'on:<instance id>'")
    out_group = instance_group(request.group)
    items, notes = resolve_plan(request, plan)
    items = [_bad_size(it) for it in items]
    if not items:
        return PlacementResult((), (), 0.0, time.perf_counter() - t0, {"nodes": 0, "notes": notes})
    sizes = _sizes(catalog, request)
    problem: FloorProblem | WallProblem | OnTopProblem
    if kind == "floor":
        problem = FloorProblem(request.room, items, cfg, rng, cfg.max_branch)
    elif kind == "wall":
        problem = WallProblem(request.room, items, request.placed, sizes, cfg, rng, cfg.max_branch)
    else:
        support = _support(request)
        if support is None:
            dropped = tuple(DroppedObject(it.record.id, out_group, f"support of group {request.group!r} is not a "
                                                                    f"placed instance") for it in items)
            return PlacementResult((), dropped, 0.0, time.perf_counter() - t0, {"nodes": 0, "notes": notes})
        sup_rec = catalog.get(support.asset)
        sizes.setdefault(support.asset, sup_rec.size)
        mesh = catalog.load_mesh(sup_rec)
        problem = OnTopProblem(request.room, items, support, sup_rec.supports, request.placed, sizes, cfg, rng,
                               cfg.max_branch, mesh, (str(catalog.root), sup_rec.id, sup_rec.mesh_file))
    result = depth_first(problem, max_backtracks=cfg.max_backtracks, patience=cfg.patience, budget_s=cfg.group_budget_s,
                         max_nodes=cfg.max_nodes)
    if result.stats.get("budget_hit"):
        log.warning("layout group %s stopped on the wall-clock budget (layout.group_budget_s = %.1f s): this layout "
                    "depends on machine load and may differ on a re-run; raise the budget for reproducible output",
                    request.group, cfg.group_budget_s)
    parent = _support(request).id if kind == "on" else None  # type: ignore[union-attr]
    item_ids: dict[int, int] = {}
    for k, ch in enumerate(result.choices):
        if ch is not None:
            item_ids[k] = next_id + len(item_ids)
    instances = []
    dropped = []
    for k, ch in enumerate(result.choices):
        rec = items[k].record
        if ch is None:
            dropped.append(DroppedObject(rec.id, out_group, result.reasons[k] or "not placed"))
            continue
        instances.append(PlacedInstance(item_ids[k], rec.id, rec.class_name, out_group,
                                        pose_matrix(ch.x, ch.y, ch.yaw, ch.z), parent,
                                        relations_for_instance(items[k], item_ids)))
    seconds = time.perf_counter() - t0
    stats = dict(result.stats, notes=notes, placed=len(instances), dropped=len(dropped))
    log.debug("%s: placed %d of %d in %.3f s (%s)", request.group, len(instances), len(items), seconds, result.stats)
    return PlacementResult(tuple(instances), tuple(dropped), result.score, seconds, stats)


def place_group_random(request: PlanRequest, catalog: Catalog, *, cfg: LayoutConfig, rng: np.random.Generator,
                       next_id: int) -> PlacementResult:
    """RandomRooms-style baseline: largest first, random (x, y) inside the room and random yaw, no
    relations and no collision reasoning; each object drops onto the floor or onto the highest
    box below its footprint. ``cfg`` is accepted for a uniform signature (nothing in it applies)."""
    t0 = time.perf_counter()
    sizes = _sizes(catalog, request)
    placed, dropped = drop_randomly(request.room, request.objects, request.placed, sizes,
                                    instance_group(request.group), rng, next_id)
    seconds = time.perf_counter() - t0
    return PlacementResult(tuple(placed), tuple(dropped), 1.0 if placed else 0.0, seconds,
                           {"placed": len(placed), "dropped": len(dropped), "seconds": seconds})
