"""Plan resolution and the relation bookkeeping shared by the floor, wall and on-top problems."""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..core.contracts import AssetRecord, PlacedInstance, Relation
from ..planning.relations import CROSS_GROUP, RELATIONS, GroupPlan, PlanRequest, review_plan
from ..core.geometry import pose_xyz_yaw
from .scoring import SATISFIED, Candidates, TargetBox, relation_score
from .search import Choice

log = logging.getLogger(__name__)

# Weight of the layout prior (walls behind objects, eye-level wall items...) next to the mean
# relation score; it only separates candidates the relations rate alike.
PRIOR_WEIGHT = 0.25


@dataclass(frozen=True)
class Item:
    """One object to place: its record, its resolved relations and, if it can never be placed,
    why. Relation targets of in-group kinds are item indices; CROSS_GROUP targets are instance ids."""

    record: AssetRecord
    relations: tuple[Relation, ...]
    forced_reason: str | None = None


def resolve_plan(request: PlanRequest, plan: GroupPlan) -> tuple[list[Item], list[str]]:
    """Turn a plan into items, repairing what is malformed instead of failing (the rules of
    :func:`~assist3d.planning.relations.review_plan`): an object whose hard relation cannot be used
    becomes an item that is never placed, with that reason. Returns the items and the notes
    describing every repair (none for a plan the layout stage already repaired)."""
    review = review_plan(plan, request)
    items = [Item(request.objects[po.source], po.relations) for po in review.plan.order]
    items += [Item(request.objects[i], (), reason) for i, reason in review.dropped]
    for note in review.notes:
        log.debug("%s", note)
    return items, list(review.notes)


class MovingBoxesMixin:
    """push/pop for search problems that keep placed items in ``self.moving`` (boxes) and
    ``self.rel`` (:class:`RelationState`)."""

    def push(self, k: int, choice) -> None:
        self.moving.add(k, choice.x, choice.y, choice.yaw, choice.z, self.items[k].record.size)  # type: ignore[attr-defined]
        self.rel.place(k, choice)  # type: ignore[attr-defined]

    def pop(self, k: int) -> None:
        self.moving.pop()  # type: ignore[attr-defined]
        self.rel.remove(k)  # type: ignore[attr-defined]


def target_box(inst: PlacedInstance, size: tuple[float, float, float]) -> TargetBox:
    x, y, z, yaw = pose_xyz_yaw(inst.pose)
    return TargetBox(x, y, yaw, float(size[0]), float(size[1]), z, z + float(size[2]))


class RelationState:
    """Scores candidates against an item's relations given the items placed so far."""

    def __init__(self, items: list[Item], cross: dict[int, TargetBox]):
        self.items = items
        self.cross = cross  # instance id -> box, for CROSS_GROUP targets
        self.boxes: dict[int, TargetBox] = {}  # item index -> box while placed

    def place(self, k: int, choice: Choice) -> None:
        w, d, h = self.items[k].record.size
        self.boxes[k] = TargetBox(choice.x, choice.y, choice.yaw, float(w), float(d), choice.z, choice.z + float(h))

    def remove(self, k: int) -> None:
        self.boxes.pop(k, None)

    def evaluate(self, k: int, c: Candidates) -> tuple[np.ndarray, np.ndarray, str]:
        """(scores (n,), hard_ok (n,) bool, description of the hard relations) for item ``k``.

        The score is the mean over the item's relations (targets not placed are left out);
        1.0 when none applies.
        """
        n = len(c)
        total = np.zeros(n)
        count = 0
        ok = np.ones(n, dtype=bool)
        hard: list[str] = []
        for r in self.items[k].relations:
            spec = RELATIONS[r.kind]
            tgt: TargetBox | None = None
            if spec.needs_target:
                tgt = self.cross.get(int(r.target)) if r.kind in CROSS_GROUP else self.boxes.get(int(r.target))  # type: ignore[arg-type]
                if tgt is None:
                    continue  # the target was dropped: nothing to relate to
            s = relation_score(r.kind, c, tgt, r.value)
            total += s
            count += 1
            if r.hard:
                ok &= s >= SATISFIED
                hard.append(f"{r.kind}({r.target})")
        scores = total / count if count else np.ones(n)
        return scores, ok, ", ".join(hard)

    def satisfying(self, k: int, c: Candidates, where: str) -> tuple[Candidates, np.ndarray, str]:
        """The candidates of item ``k`` that satisfy its hard relations and their scores, or, when
        none does, nothing and the reason (``"no free {where} satisfies hard relation(s) ..."``)."""
        score, hard_ok, hard = self.evaluate(k, c)
        if not hard_ok.any():
            return c, score, f"no free {where} satisfies hard relation(s) {hard}"
        keep = np.flatnonzero(hard_ok)
        return c.take(keep), score[keep], ""


def order_candidates(c: Candidates, rank: np.ndarray, score: np.ndarray, rng: np.random.Generator,
                     max_branch: int, spread: float) -> list[Choice]:
    """The best candidate first, then up to ``max_branch - 1`` alternatives, each at least
    ``spread`` metres (or a different yaw) away from those already chosen, so that backtracking
    tries genuinely different positions. Candidates are ordered by ``rank`` (relation score plus
    layout prior), ties broken by a seeded random key; ``score`` (the relation score alone) is
    what the choice carries."""
    n = len(c)
    if n == 0:
        return []
    key = rng.random(n)
    order = np.lexsort((key, -np.round(rank, 9)))
    out: list[int] = [int(order[0])]
    if max_branch > 1 and n > 1:
        xs, ys, yaws = c.x[order], c.y[order], c.yaw[order]
        alive = np.arange(1, n)  # ranks still free to choose, best first
        for _ in range(max_branch - 1):
            j = out[-1]
            near = np.flatnonzero(np.hypot(xs[alive] - c.x[j], ys[alive] - c.y[j]) < spread)
            same_yaw = np.abs(np.angle(np.exp(1j * (yaws[alive[near]] - c.yaw[j])))) < 1e-3
            if same_yaw.any():
                drop = np.ones(len(alive), dtype=bool)
                drop[near[same_yaw]] = False
                alive = alive[drop]
            if len(alive) == 0:
                break
            out.append(int(order[alive[0]]))
            alive = alive[1:]
    return [Choice(float(c.x[i]), float(c.y[i]), float(c.yaw[i]), float(c.z[i]), float(score[i])) for i in out]


def relations_for_instance(item: Item, item_ids: dict[int, int]) -> tuple[Relation, ...]:
    """The item's relations with in-group targets turned into instance ids (relations whose
    target was dropped are left out)."""
    out: list[Relation] = []
    for r in item.relations:
        if RELATIONS[r.kind].needs_target and r.kind not in CROSS_GROUP:
            tid = item_ids.get(int(r.target))  # type: ignore[arg-type]
            if tid is None:
                continue
            out.append(Relation(r.kind, tid, r.value, r.hard))
        else:
            out.append(r)
    return tuple(out)
