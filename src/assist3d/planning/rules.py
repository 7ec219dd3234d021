"""The rule-based relation planner: class names and sizes turned into ordered relations.

It implements :class:`assist3d.planning.relations.Planner` (``name = "rules"``) and is the offline
default and the fallback of the LLM planner. All knowledge lives in three data tables below
(:data:`FLOOR_RULES`, :data:`WALL_RULES`, :data:`ON_TOP_RULES`), keyed by canonical class names
(see :mod:`assist3d.core.taxonomy.classes`); a class not found there falls back to its head noun and then
to size-based defaults.

Ordering: objects are sorted by ``tier`` (anchors such as beds and tables first, the objects that
relate to them later) and, within a tier, by footprint area, largest first. Every relation targets
an object earlier in that order (or a placed instance for ``above``/``on``), so a plan is always
valid for :func:`~assist3d.planning.relations.validate_plan`.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..core.contracts import AssetRecord, PlacedInstance, Relation
from ..core.taxonomy.classes import canonical_class, normalise_class
from .relations import GroupPlan, PlannedObject, PlanRequest, group_kind

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class FloorRule:
    """How a floor class is placed: ``place`` globally ("edge", "middle" or None), ``hard`` makes
    the global placement a hard constraint; ``anchors`` are classes of earlier objects to relate to
    (first present wins), with ``relations`` to the chosen anchor; ``seat_width`` > 0 limits how many
    dependents share one anchor (its perimeter divided by this width, m) and ``per_anchor`` > 0 caps
    it outright."""

    tier: int
    place: str | None = None
    hard: bool = False
    anchors: tuple[str, ...] = ()
    relations: tuple[str, ...] = ()
    seat_width: float = 0.0
    per_anchor: int = 0
    binding: tuple[str, ...] = ()  # relations (of ``relations``) that are hard: the object's raison d'etre


_HUG = FloorRule(0, "edge", hard=True)
_CHAIR = FloorRule(2, None, anchors=("dining table", "table", "desk", "kitchen counter", "counter", "coffee table"),
                   relations=("around", "face_to"), seat_width=0.6, binding=("around",))

FLOOR_RULES: dict[str, FloorRule] = {
    # wall-huggers: backs against a wall, hard
    **{c: _HUG for c in ("bed", "wardrobe", "bookshelf", "shelf", "cabinet", "kitchen cabinet", "file cabinet",
                         "bathroom cabinet", "dresser", "sofa", "desk", "refrigerator", "mini fridge", "counter",
                         "kitchen counter", "bathroom counter", "bathroom vanity", "piano", "washing machine",
                         "clothes dryer", "dishwasher", "stove", "oven", "toilet", "bathtub", "fireplace", "closet",
                         "radiator", "rack", "shower", "water cooler", "copier", "printer", "vending machine",
                         "storage organizer", "furniture")},
    # free-standing tables in the middle of the room
    "table": FloorRule(1, "middle"),
    "dining table": FloorRule(1, "middle"),
    "coffee table": FloorRule(1, "middle", anchors=("sofa",), relations=("in_front_of", "near"),
                              binding=("in_front_of",)),
    # seating around tables
    "chair": _CHAIR, "stool": _CHAIR, "folded chair": _CHAIR, "seat": _CHAIR,
    "office chair": FloorRule(2, None, anchors=("desk", "table", "dining table"), relations=("in_front_of", "face_to"),
                              per_anchor=1, binding=("in_front_of",)),
    "armchair": FloorRule(2, None, anchors=("coffee table", "sofa"), relations=("near", "face_to"), per_anchor=2),
    # things beside or in front of furniture
    "nightstand": FloorRule(1, "edge", anchors=("bed",), relations=("side_of", "near", "face_same_as"),
                            per_anchor=2, binding=("side_of",)),
    "end table": FloorRule(3, None, anchors=("sofa", "armchair", "bed"), relations=("side_of", "near"),
                           binding=("side_of",)),
    "tv stand": FloorRule(1, "edge", hard=True, anchors=("sofa", "bed"), relations=("face_to",)),
    "tv": FloorRule(3, "edge", anchors=("sofa", "armchair", "bed"), relations=("face_to",)),
    "ottoman": FloorRule(3, None, anchors=("armchair", "sofa"), relations=("in_front_of", "near"),
                         binding=("in_front_of",)),
    "bench": FloorRule(3, None, anchors=("piano", "bed", "dining table"), relations=("in_front_of", "near")),
    "lamp": FloorRule(3, "edge", anchors=("bed", "sofa", "armchair", "desk"), relations=("near", "side_of")),
    "sink": FloorRule(1, "edge", hard=True, anchors=("toilet", "bathtub"), relations=("near",)),
    "trash can": FloorRule(3, "edge", anchors=("desk", "kitchen counter", "counter"), relations=("near",)),
    "recycling bin": FloorRule(4, "edge", anchors=("trash can", "desk"), relations=("side_of",)),
    "plant": FloorRule(3, "edge", anchors=("sofa", "armchair", "desk"), relations=("near",)),
    "potted plant": FloorRule(3, "edge", anchors=("sofa", "armchair", "desk"), relations=("near",)),
    "coat rack": FloorRule(3, "edge", anchors=("door",), relations=("near",)),
    "laundry basket": FloorRule(3, "edge", anchors=("washing machine", "wardrobe", "dresser"), relations=("near",)),
    "guitar": FloorRule(3, "edge", anchors=("piano", "sofa"), relations=("near",)),
    "suitcase": FloorRule(3, "edge", anchors=("wardrobe", "bed"), relations=("near",)),
    "mat": FloorRule(3, "middle", anchors=("bed", "sofa"), relations=("in_front_of",)),
}


@dataclass(frozen=True)
class WallRule:
    """Base height range above the floor (m) and floor classes to hang above (first present wins)."""

    height: tuple[float, float]
    above: tuple[str, ...] = ()


_ART = WallRule((1.2, 1.7), ("sofa", "bed", "dresser", "desk", "table", "dining table", "cabinet", "bench"))
WALL_RULES: dict[str, WallRule] = {
    **{c: _ART for c in ("picture", "poster", "decoration", "sign", "calendar", "bulletin board")},
    "mirror": WallRule((1.0, 1.5), ("sink", "bathroom vanity", "dresser")),
    "clock": WallRule((1.6, 2.0), ("sofa", "desk", "table", "dining table")),
    "alarm clock": WallRule((1.6, 2.0)),
    "tv": WallRule((0.9, 1.4), ("tv stand", "dresser", "cabinet")),
    "monitor": WallRule((0.9, 1.4), ("desk", "tv stand")),
    "shelf": WallRule((1.1, 1.6), ("desk", "table", "sofa", "bed")),
    "bookshelf": WallRule((1.1, 1.6), ("desk", "table")),
    "cabinet": WallRule((1.2, 1.6), ("counter", "desk", "sink")),
    "kitchen cabinet": WallRule((1.3, 1.6), ("kitchen counter", "counter", "stove", "sink", "dishwasher")),
    "bathroom cabinet": WallRule((1.2, 1.6), ("sink", "bathroom vanity", "toilet")),
    "range hood": WallRule((1.5, 1.8), ("stove", "oven")),
    "whiteboard": WallRule((0.8, 1.1), ("desk", "table")),
    "blackboard": WallRule((0.8, 1.1), ("desk", "table")),
    "projector screen": WallRule((0.8, 1.2)),
    "radiator": WallRule((0.05, 0.3)),
    "vent": WallRule((0.1, 0.4)),
    "power outlet": WallRule((0.2, 0.4)),
    "light switch": WallRule((1.0, 1.3)),
    "light": WallRule((1.6, 2.0), ("bed", "sofa", "desk", "mirror")),
    "lamp": WallRule((1.6, 2.0), ("bed", "sofa", "desk")),
    "coat rack": WallRule((1.4, 1.8)),
    "towel": WallRule((0.9, 1.4), ("bathtub", "sink", "toilet")),
    "paper towel dispenser": WallRule((1.0, 1.4), ("sink",)),
    "soap dispenser": WallRule((1.0, 1.3), ("sink",)),
    "toilet paper holder": WallRule((0.6, 0.8), ("toilet",)),
    "fire extinguisher": WallRule((0.8, 1.2)),
    "fan": WallRule((1.8, 2.3)),
    "speaker": WallRule((1.6, 2.1), ("tv stand", "sofa")),
    "curtain": WallRule((0.0, 0.3)),
}
DEFAULT_WALL_HEIGHT = (1.0, 1.7)


@dataclass(frozen=True)
class OnTopRule:
    """Earlier siblings to relate to (first present wins) and the relations to it."""

    tier: int
    anchors: tuple[str, ...] = ()
    relations: tuple[str, ...] = ()


ON_TOP_RULES: dict[str, OnTopRule] = {
    "monitor": OnTopRule(0), "tv": OnTopRule(0), "laptop": OnTopRule(0), "lamp": OnTopRule(0),
    "computer tower": OnTopRule(0), "printer": OnTopRule(0), "microwave": OnTopRule(0),
    "keyboard": OnTopRule(1, ("monitor", "computer tower"), ("in_front_of", "center_aligned", "face_same_as")),
    "mouse": OnTopRule(2, ("keyboard", "laptop"), ("right_of", "near")),
    "speaker": OnTopRule(1, ("monitor", "tv"), ("side_of",)),
    "headphones": OnTopRule(2, ("laptop", "keyboard", "monitor"), ("near",)),
    "cup": OnTopRule(2, ("plate", "laptop", "book", "coffee maker"), ("near",)),
    "bottle": OnTopRule(3, ("cup", "bowl", "plate"), ("near",)),
    "water bottle": OnTopRule(3, ("cup", "laptop"), ("near",)),
    "bowl": OnTopRule(2, ("plate",), ("near",)),
    "plate": OnTopRule(1),
    "book": OnTopRule(1, ("book", "lamp"), ("side_of",)),
    "pillow": OnTopRule(1, ("pillow",), ("side_of", "face_same_as")),
    "cushion": OnTopRule(2, ("cushion", "pillow"), ("side_of", "face_same_as")),
    "telephone": OnTopRule(2, ("monitor", "laptop", "lamp"), ("near",)),
    "alarm clock": OnTopRule(2, ("lamp",), ("side_of",)),
    "candle": OnTopRule(3, ("plant", "potted plant", "decoration"), ("near",)),
    "potted plant": OnTopRule(1), "plant": OnTopRule(1), "decoration": OnTopRule(2),
}


def _lookup(table: dict, class_name: str):
    """The rule of a class: by canonical name, then the head noun's canonical name; None if absent."""
    c = canonical_class(class_name)
    if c in table:
        return table[c]
    n = normalise_class(class_name)
    if " " in n:
        head = canonical_class(n.rsplit(" ", 1)[1])
        if head in table:
            return table[head]
    return None


def _footprint(r: AssetRecord) -> float:
    return float(r.size[0]) * float(r.size[1])


def _is_big(r: AssetRecord) -> bool:
    return _footprint(r) >= 0.6 or max(r.size[0], r.size[1]) >= 1.2


def _order(objects: tuple[AssetRecord, ...], tiers: list[int]) -> list[int]:
    keys = [(tiers[i], -round(_footprint(r), 6), canonical_class(r.class_name), r.id, i) for i, r in enumerate(objects)]
    return [k[-1] for k in sorted(keys)]


class RulePlanner:
    """Deterministic, offline relation planner driven by class names and sizes."""

    name = "rules"

    def __init__(self, *, near_prob: float = 0.5, binding: bool = True):
        # probability that an object of an unknown small class is placed near a random earlier object
        self.near_prob = float(near_prob)
        # make each rule's defining relations (chairs around a table, nightstands beside a bed) hard:
        # an object that cannot keep them is dropped rather than placed anywhere
        self.binding = bool(binding)

    def plan(self, request: PlanRequest, *, rng: np.random.Generator) -> GroupPlan:
        kind = group_kind(request.group)
        if kind == "floor":
            order = self._plan_floor(request.objects, rng)
        elif kind == "wall":
            order = self._plan_wall(request.objects, request.placed, request.room.height, rng)
        else:
            order = self._plan_on_top(request.objects, request.support, rng)
        return GroupPlan(group=request.group, order=tuple(order), planner=self.name)

    # ------------------------------------------------------------------ floor

    def _plan_floor(self, objects: tuple[AssetRecord, ...], rng: np.random.Generator) -> list[PlannedObject]:
        rules = [_lookup(FLOOR_RULES, r.class_name) for r in objects]
        tiers = [ru.tier if ru is not None else (0 if _is_big(r) else 2) for r, ru in zip(objects, rules)]
        order = _order(objects, tiers)
        classes: list[str] = []  # canonical class per planned position
        dependents: list[int] = []  # number of objects anchored to each planned position
        out: list[PlannedObject] = []
        for pos, src in enumerate(order):
            rec, rule = objects[src], rules[src]
            rels: list[Relation] = []
            anchor = self._anchor(rule, rec, classes, dependents, objects, order) if rule is not None else None
            if rule is not None and rule.place is not None:
                rels.append(Relation(rule.place, None, (), rule.hard))
            if anchor is not None:
                dependents[anchor] += 1
                rels.extend(Relation(k, anchor, (), self.binding and k in rule.binding) for k in rule.relations)
            elif rule is None or (rule.place is None and rule.anchors):
                rels.extend(self._default_floor(rec, pos, rng))
            classes.append(canonical_class(rec.class_name))
            dependents.append(0)
            out.append(PlannedObject(src, tuple(rels)))
        return out

    @staticmethod
    def _anchor(rule: FloorRule, rec: AssetRecord, classes: list[str], dependents: list[int],
                objects: tuple[AssetRecord, ...], order: list[int]) -> int | None:
        """The earlier position this object relates to: the first anchor class present, the
        candidate with the fewest dependents below its capacity (ties: earliest)."""
        for cls in rule.anchors:
            cands = [p for p, c in enumerate(classes) if c == cls]
            if not cands:
                continue
            if rule.seat_width > 0 or rule.per_anchor > 0:
                def capacity(p: int) -> int:
                    w, d = objects[order[p]].size[0], objects[order[p]].size[1]
                    seats = max(1, int(2 * (w + d) // rule.seat_width)) if rule.seat_width > 0 else 1 << 30
                    return min(seats, rule.per_anchor) if rule.per_anchor > 0 else seats
                cands = [p for p in cands if dependents[p] < capacity(p)]
            if cands:
                return min(cands, key=lambda p: (dependents[p], p))
        return None

    def _default_floor(self, rec: AssetRecord, pos: int, rng: np.random.Generator) -> list[Relation]:
        if _is_big(rec):
            return [Relation("edge")]
        if pos > 0 and rng.random() < self.near_prob:
            return [Relation("near", int(rng.integers(pos)))]
        return [Relation("middle")]

    # ------------------------------------------------------------------ wall

    def _plan_wall(self, objects: tuple[AssetRecord, ...], placed: tuple[PlacedInstance, ...], room_height: float,
                   rng: np.random.Generator) -> list[PlannedObject]:
        # widest first
        order = sorted(range(len(objects)), key=lambda i: (-round(objects[i].size[0], 6), objects[i].id, i))
        floor_by_class: dict[str, list[int]] = {}
        for inst in placed:
            if inst.group == "floor":
                floor_by_class.setdefault(canonical_class(inst.class_name), []).append(inst.id)
        used_above: dict[int, int] = {}
        classes: list[str] = []
        out: list[PlannedObject] = []
        for pos, src in enumerate(order):
            rec = objects[src]
            rule = _lookup(WALL_RULES, rec.class_name)
            if rule is not None:
                lo, hi = rule.height
            elif rec.elevation > 0:
                lo, hi = rec.elevation - 0.15, rec.elevation + 0.15
            else:
                lo, hi = DEFAULT_WALL_HEIGHT
            top = room_height - float(rec.size[2]) - 0.05
            hi = max(0.0, min(hi, top))
            lo = max(0.0, min(lo, hi))
            rels = [Relation("height", None, (round(lo, 4), round(hi, 4)), False)]
            if rule is not None:
                for cls in rule.above:
                    ids = floor_by_class.get(cls)
                    if ids:
                        fewest = min(used_above.get(i, 0) for i in ids)
                        free = [i for i in ids if used_above.get(i, 0) == fewest]
                        target = free[int(rng.integers(len(free)))]
                        used_above[target] = used_above.get(target, 0) + 1
                        rels.append(Relation("above", target))
                        break
            me = canonical_class(rec.class_name)
            same = [p for p, c in enumerate(classes) if c == me]
            if same and len(rels) == 1:
                rels.append(Relation("side_of", same[-1]))
            classes.append(me)
            out.append(PlannedObject(src, tuple(rels)))
        return out

    # ------------------------------------------------------------------ on top

    def _plan_on_top(self, objects: tuple[AssetRecord, ...], support: PlacedInstance | None,
                     rng: np.random.Generator) -> list[PlannedObject]:
        rules = [_lookup(ON_TOP_RULES, r.class_name) for r in objects]
        tiers = [ru.tier if ru is not None else 1 for ru in rules]
        order = _order(objects, tiers)
        classes: list[str] = []
        out: list[PlannedObject] = []
        for pos, src in enumerate(order):
            rec, rule = objects[src], rules[src]
            rels: list[Relation] = []
            if support is not None:
                rels.append(Relation("on", support.id, (), True))
            anchor = None
            if rule is not None:
                for cls in rule.anchors:
                    cands = [p for p, c in enumerate(classes) if c == cls]
                    if cands:
                        anchor = cands[-1]
                        break
            if anchor is not None:
                rels.extend(Relation(k, anchor) for k in rule.relations)
            elif rule is None and pos > 0 and rng.random() < self.near_prob:
                rels.append(Relation("near", int(rng.integers(pos))))
            classes.append(canonical_class(rec.class_name))
            out.append(PlannedObject(src, tuple(rels)))
        return out
