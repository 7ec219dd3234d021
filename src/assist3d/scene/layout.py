"""The layout facade: room, selection, relation planning and placement for one scene.

``build_layout(catalog, cfg, seed)`` runs, each stage with its own random stream
(``make_rng(seed, "room")``, ``"select"``, ``("plan", group)``, ``("place", group)``):

1. sample the room shell;
2. select floor, wall and on-top assets;
3. plan and place the floor group, then the wall group (knowing the floor instances), then, for
   every placed instance with a support surface, its on-top group ``on:<id>``. An on-top group's
   plan depends only on its objects, the room and its support, so with an LLM planner every on-top
   group of the scene is planned at once (``llm.concurrency`` requests, ``llm.plan_concurrently``)
   before they are placed one after another in the usual order: the same answers give the same
   layout whatever order they arrive in; with ``llm.on_top_batch`` > 1 they are asked for that many
   to a prompt. ``llm.scene_budget_s`` bounds a scene's planning time:
   a group whose planning starts after it is planned by the rules, with a note.

Nothing here raises for an impossible scene: plans with unknown relations, targets or duplicate
objects are repaired (constraints dropped, with a note; an object whose *hard* relation is broken
is dropped), placement failures become dropped objects with reasons, and on-top objects whose
parent was not placed are dropped as "parent not placed".
"""

from __future__ import annotations

import logging
import time
from collections import defaultdict, deque
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Callable

from ..assets.catalog import Catalog
from ..config import GenerateConfig
from ..core.contracts import AssetRecord, DroppedObject, LayoutStats, PlacedInstance, SceneLayout, group_kind, on_top_group
from ..core.errors import AssistError
from ..placement import PlacementResult, place_group, place_group_random
from ..planning.planners import make_planner
from ..planning.relations import GroupPlan, Planner, PlanRequest, review_plan
from ..planning.rules import RulePlanner
from ..core.records import PLAN_COUNTERS
from ..core.rng import make_rng
from .room import fill_openings, sample_room
from .selection import Selection, select_objects

log = logging.getLogger(__name__)

MAX_NOTES = 50


@dataclass(frozen=True)
class Placer:
    """The placement engine a layout uses: ``place`` for planned groups (bounded depth-first search)
    and ``place_random`` for the RandomRooms-style baseline; both take ``(request, [plan,] catalog,
    *, cfg, rng, next_id)`` and return a :class:`~assist3d.placement.PlacementResult`.
    Tests pass stand-ins to :func:`build_layout`."""

    place: Callable[..., PlacementResult] = place_group
    place_random: Callable[..., PlacementResult] = place_group_random


def sanitise_plan(plan: GroupPlan, request: PlanRequest) -> tuple[GroupPlan, list[DroppedObject], list[str]]:
    """The well-formed plan of :func:`~assist3d.planning.relations.review_plan`, the objects it took
    out as dropped objects (with reasons) and the notes describing every repair."""
    review = review_plan(plan, request)
    dropped = [DroppedObject(request.objects[i].id, request.group, reason) for i, reason in review.dropped]
    if dropped:
        log.debug("%s: %d object(s) dropped by the plan repair", request.group, len(dropped))
    return review.plan, dropped, list(review.notes)


@dataclass(frozen=True)
class _Planned:
    """A group's plan made ahead of its placement, with the notes to record when it is placed."""

    plan: GroupPlan
    notes: tuple[str, ...]
    over_budget: bool


@dataclass(frozen=True)
class _OnTopJob:
    """One on-top group to plan and place (``support`` None: its parent was not placed)."""

    group: str
    objects: tuple[AssetRecord, ...]
    support: PlacedInstance | None


@dataclass
class _Run:
    """Mutable bookkeeping of one build_layout call."""

    catalog: Catalog
    cfg: GenerateConfig
    seed: int
    planner: Planner
    room: object
    placer: Placer
    instances: list[PlacedInstance] = field(default_factory=list)
    dropped: list[DroppedObject] = field(default_factory=list)
    planners: dict = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    plan_stats: dict = field(default_factory=lambda: defaultdict(float))
    place_stats: dict = field(default_factory=lambda: defaultdict(float))
    timing: dict = field(default_factory=dict)
    deadline: float | None = None  # monotonic time after which groups are planned by the rules
    budget_s: float | None = None
    over_budget: int = 0

    @property
    def next_id(self) -> int:
        return 1 + max((i.id for i in self.instances), default=0)

    def plan_ahead(self, request: PlanRequest) -> _Planned:
        """Plan one group without touching the run's records (safe to call from several threads)."""
        return self.plan_ahead_many([request])[request.group]

    def plan_ahead_many(self, requests: list[PlanRequest]) -> dict[str, _Planned]:
        """Plan one group, or several on-top groups with one prompt (``llm.on_top_batch``), by group name,
        without touching the run's records. Past the scene's budget, or when the planner fails, the
        rules plan each group, with a note."""
        rngs = [make_rng(self.seed, "plan", r.group) for r in requests]
        if self.deadline is not None and time.monotonic() >= self.deadline:
            return {r.group: _Planned(RulePlanner().plan(r, rng=g),
                                      (f"{r.group}: the scene's LLM planning budget ({self.budget_s:g} s) was "
                                       f"spent; rule-based plan used",), True) for r, g in zip(requests, rngs)}
        try:
            plans = (self.planner.plan_batch(requests, rngs=rngs) if len(requests) > 1  # type: ignore[attr-defined]
                     else [self.planner.plan(requests[0], rng=rngs[0])])
            return {p.group: _Planned(p, (), False) for p in plans}
        except AssistError as e:
            return {r.group: _Planned(RulePlanner().plan(r, rng=g),
                                      (f"{r.group}: planner {self.planner.name} failed ({e}); rule-based plan used",),
                                      False) for r, g in zip(requests, rngs)}

    def plan_many(self, requests: list[PlanRequest], workers: int) -> dict[str, _Planned]:
        """Plans of ``requests`` made ``workers`` at a time (with ``llm.on_top_batch`` > 1, in
        prompts of that many groups, in ``requests`` order); recorded only when each group is placed."""
        batch = self.cfg.llm.on_top_batch if hasattr(self.planner, "plan_batch") else 1
        if batch <= 1 and (workers <= 1 or len(requests) <= 1):
            return {}  # planned one by one as they are placed
        t0 = time.perf_counter()
        chunks = [requests[i:i + batch] for i in range(0, len(requests), batch)]  # batch >= 1 (llm.on_top_batch)
        planned: dict[str, _Planned] = {}
        with ThreadPoolExecutor(max_workers=max(1, min(workers, len(chunks))), thread_name_prefix="plan") as pool:
            for part in pool.map(self.plan_ahead_many, chunks):
                planned.update(part)
        self.timing["plan_on_top"] = round(time.perf_counter() - t0, 4)
        return planned

    def record_plan(self, planned: _Planned) -> GroupPlan:
        self.notes.extend(planned.notes)
        self.over_budget += int(planned.over_budget)
        self.add_plan_stats(planned.plan.stats)
        return planned.plan

    def add_plan_stats(self, stats: dict) -> None:
        """Sum a planner call's counters (LLM calls, cache hits, tokens, seconds) into the layout's."""
        for k in PLAN_COUNTERS:
            v = stats.get(k)
            if isinstance(v, (int, float)):
                self.plan_stats[k] += v

    def run_group(self, group: str, objects: tuple[AssetRecord, ...], support: PlacedInstance | None,
                  random_mode: bool, planned: _Planned | None = None) -> list[int | None]:
        """Plan (unless ``planned`` holds its plan) and place one group. Returns, for each object,
        the id of its placed instance or None."""
        t0 = time.perf_counter()
        placed_before = tuple(self.instances)
        # the placement sees every instance so far (collisions with wall shelves above a table...);
        # the planner of an on-top group only its support (short LLM prompts, stable cache keys)
        request = PlanRequest(group, objects, self.room, placed_before, support)  # type: ignore[arg-type]
        plan_request = request
        if support is not None:
            plan_request = PlanRequest(group, objects, self.room, (support,), support)  # type: ignore[arg-type]
        place_rng = make_rng(self.seed, "place", group)
        extra_dropped: list[DroppedObject] = []
        order: list[int] = list(range(len(objects)))
        try:
            if random_mode:
                self.planners[group] = "none"
                result = self.placer.place_random(request, self.catalog, cfg=self.cfg.layout, rng=place_rng,
                                                  next_id=self.next_id)
            else:
                plan = self.record_plan(planned if planned is not None else self.plan_ahead(plan_request))
                self.notes.extend(plan.notes)
                plan, extra_dropped, notes = sanitise_plan(plan, plan_request)
                self.notes.extend(notes)
                self.planners[group] = plan.planner
                order = [p.source for p in plan.order]
                result = self.placer.place(request, plan, self.catalog, cfg=self.cfg.layout, rng=place_rng,
                                           next_id=self.next_id)
        except AssistError as e:
            reason = f"placement failed: {e}"
            self.dropped.extend(DroppedObject(r.id, group, reason) for r in objects)
            self.timing[group] = round(time.perf_counter() - t0, 4)
            return [None] * len(objects)
        self.instances.extend(result.instances)
        self.dropped.extend(extra_dropped)
        self.dropped.extend(result.dropped)
        self.notes.extend(str(n) for n in (result.stats or {}).get("notes", ()) or ())
        for k, v in (result.stats or {}).items():
            if isinstance(v, (int, float)) and "second" not in k and "time" not in k:
                self.place_stats[k] += int(v) if isinstance(v, bool) else v  # flags summed: groups that hit it
        self.timing[group] = round(time.perf_counter() - t0, 4)
        # map placed instances back to the selected objects (the same asset may be selected twice)
        queue: dict[str, deque[int]] = defaultdict(deque)
        in_order = set(order)
        for src in order + [i for i in range(len(objects)) if i not in in_order]:
            queue[objects[src].id].append(src)
        ids: list[int | None] = [None] * len(objects)
        for inst in result.instances:
            q = queue.get(inst.asset)
            if q:
                ids[q.popleft()] = inst.id
        return ids

    def on_top_jobs(self, ids: list[int | None], lists: tuple[tuple[AssetRecord, ...], ...]) -> list[_OnTopJob]:
        jobs = []
        for inst_id, items in zip(ids, lists):
            if not items:
                continue
            support = None if inst_id is None else next(i for i in self.instances if i.id == inst_id)
            jobs.append(_OnTopJob(on_top_group(inst_id), items, support))
        return jobs

    def on_top(self, jobs: list[_OnTopJob], random_mode: bool, workers: int) -> None:
        """Plan the on-top groups (``workers`` at a time) and place them in ``jobs`` order."""
        planned: dict[str, _Planned] = {}
        if not random_mode:
            planned = self.plan_many([PlanRequest(j.group, j.objects, self.room, (j.support,), j.support)  # type: ignore[arg-type]
                                      for j in jobs if j.support is not None], workers)
        for j in jobs:
            if j.support is None:
                self.dropped.extend(DroppedObject(r.id, "obj", "parent not placed") for r in j.objects)
            else:
                self.run_group(j.group, j.objects, j.support, random_mode, planned.get(j.group))


def build_layout(catalog: Catalog, cfg: GenerateConfig, seed: int, *, scene_index: int = 0,
                 planner: Planner | None = None, placer: Placer | None = None) -> SceneLayout:
    """One scene's layout. The same (catalog, cfg, seed, scene_index) gives the same layout
    (timings aside: ``stats["timing"]`` holds wall seconds of the selection as ``"select"``, of
    each group by its name and of LLM calls as ``"llm_seconds"``). ``planner`` defaults to
    :func:`~assist3d.planning.planners.make_planner`, ``placer`` to the placement engine."""
    t0 = time.perf_counter()
    planner = planner if planner is not None else make_planner(cfg)
    room = sample_room(cfg.room, make_rng(seed, "room"))
    propose: Callable | None = None
    if cfg.selection.strategy == "room-type" and hasattr(planner, "propose_room"):
        def ask_planner(room_type: str, vocab: dict[str, tuple[str, ...]]):
            return planner.propose_room(room_type, room, vocab)
        propose = ask_planner
    sel: Selection = select_objects(catalog, cfg.selection, make_rng(seed, "select"), scene_index=scene_index,
                                    propose=propose)
    run = _Run(catalog, cfg, seed, planner, room, placer if placer is not None else Placer())
    uses_llm = not isinstance(planner, RulePlanner)
    if uses_llm and cfg.llm.scene_budget_s is not None:
        run.budget_s = cfg.llm.scene_budget_s
        run.deadline = time.monotonic() + cfg.llm.scene_budget_s
    workers = cfg.llm.concurrency if uses_llm and cfg.llm.plan_concurrently else 1
    run.timing["select"] = round(time.perf_counter() - t0, 4)  # planner, room and selection
    room_llm = sel.stats.get("room_llm")
    if room_llm:  # the LLM's object plan counts with the planning calls
        run.add_plan_stats(room_llm)
        run.notes.extend(str(n) for n in room_llm.get("notes", ()))
    random_mode = cfg.layout.planner == "none"
    floor_ids = run.run_group("floor", sel.floor, None, random_mode) if sel.floor else []
    wall_ids = run.run_group("wall", sel.wall, None, random_mode) if sel.wall else []
    run.on_top(run.on_top_jobs(floor_ids, sel.floor_on_top) + run.on_top_jobs(wall_ids, sel.wall_on_top),
               random_mode, workers)

    placed = {g: 0 for g in ("floor", "wall", "obj")}
    for inst in run.instances:
        placed[group_kind(inst.group)] += 1
    stats = LayoutStats(
        selected={"floor": len(sel.floor), "wall": len(sel.wall),
                  "obj": sum(map(len, sel.floor_on_top)) + sum(map(len, sel.wall_on_top))},
        placed=placed,
        dropped=len(run.dropped),
        selection=dict(sel.stats),
        llm_calls=int(run.plan_stats.get("llm_calls", 0)),
        cache_hits=int(run.plan_stats.get("cache_hits", 0)),
        repairs=int(run.plan_stats.get("repairs", 0)),
        placement={k: (int(v) if float(v).is_integer() else round(v, 6)) for k, v in sorted(run.place_stats.items())},
        notes=run.notes[:MAX_NOTES],
        timing=run.timing,
        # groups the rules planned because the LLM budget was spent (only with a budget)
        llm_budget_groups=run.over_budget if run.budget_s is not None else None,
        prompt_tokens=int(run.plan_stats["prompt_tokens"]) if "prompt_tokens" in run.plan_stats else None,
        completion_tokens=int(run.plan_stats["completion_tokens"]) if "completion_tokens" in run.plan_stats else None,
    )
    if run.plan_stats.get("llm_seconds"):
        run.timing["llm_seconds"] = round(float(run.plan_stats["llm_seconds"]), 4)  # wall time: kept with timings
    if cfg.room.fill_openings:  # its own random stream: every other draw of the scene is unchanged
        first = max((inst.id for inst in run.instances), default=0) + 1
        room = fill_openings(room, first, cfg.layout.door_clearance, make_rng(seed, "openings"))
    seconds = time.perf_counter() - t0
    log.debug("layout seed %d: %d placed, %d dropped, %.3f s", seed, len(run.instances), len(run.dropped), seconds)
    return SceneLayout(room=room, instances=tuple(run.instances), dropped=tuple(run.dropped), seed=int(seed),
                       seconds=seconds, planner=dict(run.planners), stats=stats)


def layout_summary(layout: SceneLayout) -> dict:
    """Counts for a one-line report: placed per group, dropped, seconds."""
    placed = {g: 0 for g in ("floor", "wall", "obj")}
    for inst in layout.instances:
        placed[group_kind(inst.group)] += 1
    return {"placed": placed, "instances": len(layout.instances), "dropped": len(layout.dropped),
            "seconds": round(layout.seconds, 3)}
