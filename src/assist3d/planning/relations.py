"""The relation vocabulary and the planner interface shared by the rule-based and LLM planners.

A planner receives the objects selected for one group (the floor objects, the wall objects, or
the on-top objects of one support) and returns them in placement order, each with relations to
objects *earlier in that order* only. The depth-first placement search turns relations into
poses: ``hard`` relations filter candidate placements, soft ones rank them.

Group names: ``"floor"``, ``"wall"``, and ``"on:<support instance id>"`` for on-top groups.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Container, Protocol, Sequence

import numpy as np

from ..core.contracts import AssetRecord, PlacedInstance, Relation, Room, on_top_support


@dataclass(frozen=True)
class RelationSpec:
    """What a relation kind means and what it needs."""

    kind: str
    needs_target: bool
    groups: tuple[str, ...]  # which groups may use it: "floor", "wall", "on"
    values: int  # number of numbers in Relation.value
    description: str


_SPECS = (
    RelationSpec("edge", False, ("floor",), 0, "back against a wall"),
    RelationSpec("middle", False, ("floor",), 0, "away from the walls"),
    RelationSpec("near", True, ("floor", "wall", "on"), 0, "within about 0.5-1.5 m of the target"),
    RelationSpec("far", True, ("floor", "wall", "on"), 0, "at least about 1.5 m from the target"),
    RelationSpec("in_front_of", True, ("floor", "on"), 0, "in the target's front half-space"),
    RelationSpec("behind", True, ("floor", "on"), 0, "in the target's back half-space"),
    RelationSpec("left_of", True, ("floor", "wall", "on"), 0, "on the target's left (seen from its front)"),
    RelationSpec("right_of", True, ("floor", "wall", "on"), 0, "on the target's right (seen from its front)"),
    RelationSpec("side_of", True, ("floor", "wall", "on"), 0, "beside the target, left or right"),
    RelationSpec("around", True, ("floor",), 0, "near the target and facing it (chairs around a table)"),
    RelationSpec("center_aligned", True, ("floor", "wall", "on"), 0, "centre aligned with the target on one axis"),
    RelationSpec("face_to", True, ("floor",), 0, "front turned towards the target"),
    RelationSpec("face_same_as", True, ("floor", "wall", "on"), 0, "same orientation as the target"),
    RelationSpec("height", False, ("wall",), 2, "base height above the floor within [value0, value1] m"),
    RelationSpec("above", True, ("wall",), 0, "above a floor object (target = a floor instance id)"),
    RelationSpec("on", True, ("on",), 0, "rests on the support (target = the support instance id)"),
)

RELATIONS: dict[str, RelationSpec] = {s.kind: s for s in _SPECS}

# Relations whose target is an instance id of an already-placed object of another group rather
# than an index into the current group's plan.
CROSS_GROUP = frozenset({"above", "on"})


def group_kind(group: str) -> str:
    """'floor', 'wall' or 'on' for a group name."""
    return "on" if on_top_support(group) is not None else group


@dataclass(frozen=True)
class PlanRequest:
    """The objects of one group to order and relate.

    ``objects`` are the selected assets (any order); ``placed`` are instances already placed in
    the scene (floor objects when planning walls, the support when planning an on-top group);
    ``support`` is the support instance for on-top groups.
    """

    group: str
    objects: tuple[AssetRecord, ...]
    room: Room
    placed: tuple[PlacedInstance, ...] = ()
    support: PlacedInstance | None = None


@dataclass(frozen=True)
class PlannedObject:
    """``source`` indexes ``PlanRequest.objects``; relation targets index earlier PlannedObjects
    (or, for CROSS_GROUP kinds, are instance ids)."""

    source: int
    relations: tuple[Relation, ...] = ()


@dataclass(frozen=True)
class GroupPlan:
    group: str
    order: tuple[PlannedObject, ...]
    planner: str  # "rules" | "llm:<model>" | "none"
    notes: tuple[str, ...] = ()  # e.g. constraints dropped and why
    stats: dict = field(default_factory=dict)  # llm_calls, cache_hits, repairs, tokens, seconds


class Planner(Protocol):
    """Anything with a name and ``plan(request, rng=...) -> GroupPlan``."""

    name: str

    def plan(self, request: PlanRequest, *, rng: np.random.Generator) -> GroupPlan: ...


def relation_problem(r: Relation, kind: str, placed_ids: Container[int], earlier: Container[int]) -> str | None:
    """Why relation ``r`` of a ``kind`` ('floor' | 'wall' | 'on') object cannot be used, or None.

    ``placed_ids``: instance ids a CROSS_GROUP target may name; ``earlier``: plan positions an
    in-group target may name (the objects before this one)."""
    spec = RELATIONS.get(r.kind)
    if spec is None:
        return f"unknown relation {r.kind!r}"
    if kind not in spec.groups:
        return f"relation {r.kind!r} is not allowed for {kind} objects"
    if len(r.value) != spec.values:
        return f"relation {r.kind!r} needs {spec.values} value(s), got {len(r.value)}"
    if r.kind == "height" and not r.value[0] <= r.value[1]:
        return f"relation 'height' has an empty range {tuple(r.value)}"
    if spec.needs_target:
        if r.target is None:
            return f"relation {r.kind!r} has no target"
        if r.kind in CROSS_GROUP:
            if r.target not in placed_ids:
                return f"relation {r.kind!r} to unknown instance {r.target} (not a placed instance)"
        elif r.target not in earlier:
            return f"relation {r.kind!r} to unknown or later object {r.target} (not an earlier object of the plan)"
    return None


@dataclass(frozen=True)
class PlanReview:
    """One reading of a plan against its request (:func:`review_plan`).

    ``plan``: the well-formed plan: out-of-range and repeated entries removed, soft relations that
    cannot be used removed, objects whose *hard* relation cannot be used taken out, forgotten
    objects appended without relations; in-group targets renumbered to the kept positions.
    ``dropped``: ``(object index, reason)`` of the objects taken out. ``notes``: every repair, for
    the layout's notes. ``problems``: the plan as written judged strictly (positions as the
    planner wrote them), for a planner that asks its author to fix the plan; empty means the plan
    is well-formed as it is.
    """

    plan: GroupPlan
    dropped: tuple[tuple[int, str], ...]
    notes: tuple[str, ...]
    problems: tuple[str, ...]


def review_plan(plan: GroupPlan, request: PlanRequest) -> PlanReview:
    """Check and repair ``plan`` for ``request``: the one set of plan rules every caller uses
    (the layout stage, the placement engine, the LLM planner's repair loop)."""
    kind = group_kind(request.group)
    placed_ids = {p.id for p in request.placed} | ({request.support.id} if request.support else set())
    problems: list[str] = []
    notes: list[str] = []
    dropped: list[tuple[int, str]] = []
    seen: set[int] = set()
    new_pos: dict[int, int] = {}  # position in the plan as written -> position in the repaired plan
    kept: list[PlannedObject] = []
    for pos, item in enumerate(plan.order):
        if not 0 <= item.source < len(request.objects):
            problems.append(f"position {pos}: object index {item.source} out of range")
            notes.append(f"{request.group}: position {pos}: object index {item.source} out of range; ignored")
            continue
        repeated = item.source in seen
        if repeated:
            problems.append(f"position {pos}: object {item.source} listed twice")
            notes.append(f"{request.group}: position {pos}: object {item.source} listed twice; kept the first")
        seen.add(item.source)
        rec = request.objects[item.source]
        rels: list[Relation] = []
        broken_hard: str | None = None
        for r in item.relations:
            strict = relation_problem(r, kind, placed_ids, range(pos))
            if strict is not None:
                problems.append(f"position {pos}: {strict}")
            if repeated or broken_hard is not None:
                continue
            problem = relation_problem(r, kind, placed_ids, new_pos)
            if problem is None:
                rels.append(Relation(r.kind, new_pos[r.target] if _indexes_plan(r) else r.target,  # type: ignore[index]
                                     r.value, r.hard))
            elif r.hard:
                broken_hard = problem
            else:
                notes.append(f"{request.group}: {rec.class_name} ({rec.id}): dropped relation: {problem}")
        if repeated:
            continue
        if broken_hard is not None:
            dropped.append((item.source, f"hard relation unusable: {broken_hard}"))
            continue
        new_pos[pos] = len(kept)
        kept.append(PlannedObject(item.source, tuple(rels)))
    missing = [i for i in range(len(request.objects)) if i not in seen]
    if missing:
        problems.append(f"objects never planned: {missing}")
    for i in missing:
        rec = request.objects[i]
        notes.append(f"{request.group}: {rec.class_name} ({rec.id}) missing from the plan; appended without relations")
        kept.append(PlannedObject(i))
    fixed = GroupPlan(plan.group, tuple(kept), plan.planner, plan.notes + tuple(notes), dict(plan.stats))
    return PlanReview(fixed, tuple(dropped), tuple(notes), tuple(problems))


def _indexes_plan(r: Relation) -> bool:
    """Whether ``r``'s target is a position in the group's plan (not an instance id)."""
    spec = RELATIONS.get(r.kind)
    return spec is not None and spec.needs_target and r.kind not in CROSS_GROUP


def validate_plan(plan: GroupPlan, request: PlanRequest) -> list[str]:
    """Problems with a plan as written: unknown kinds, targets that are not earlier objects,
    duplicates, missing objects. An empty list means the plan is well-formed."""
    return list(review_plan(plan, request).problems)


def canonical_relation_names() -> Sequence[str]:
    return tuple(RELATIONS)
