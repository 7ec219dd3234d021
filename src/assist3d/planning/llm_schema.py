"""The JSON answer the relation planner asks for, and its validation.

Answer format (one object per line of the group's object list, in placement order)::

    {"objects": [
      {"index": 2, "relations": [{"relation": "edge"}]},
      {"index": 0, "relations": [{"relation": "near", "target": 2}, {"relation": "face_to", "target": 2}]}
    ]}

``index`` is the number the prompt gave the object; ``target`` is the index of an object listed
*earlier in the answer*, except for ``above`` / ``on`` whose target is the id of an already-placed
instance; ``height`` takes ``"value": [min_m, max_m]``; ``"hard": true|false`` is optional.

With ``llm.answer_format: compact`` the prompts ask for the same content in about a third of the
tokens (an LLM's answer time grows with its length, and the floor group's answer bounds a scene)::

    {"objects": [[2, "edge"], [0, ["near", 2], ["face_to", 2, "hard"]], [1, ["height", 1.2, 1.6]]]}

one list per object, ``[index, relation, ...]``; a relation is its name alone (``"edge"``) or a list
``[name, target]``, ``[name, min_m, max_m]`` (``height``), with ``"hard"`` or ``"soft"`` (or true /
false) last when given. Every answer may use either form, entry by entry (:func:`expand_compact_entry` turns a
compact entry into the full one before it is checked).

Several on-top groups asked for in one prompt (``llm.on_top_batch``) are answered as
``{"groups": [{"group": "on:7", "objects": [...]}, ...]}`` and each group's entry is checked as
above (:func:`split_batch_answer`).

Nothing is guessed: an unknown relation name is reported, never mapped to a close one. The
answer text is parsed with ``json.loads`` only (a Markdown code fence around it is tolerated), by
:func:`assist3d.llm.schema.parse_json_text`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

from ..core.contracts import Relation
from .relations import CROSS_GROUP, RELATIONS, PlannedObject, PlanRequest, group_kind

# Relations that are hard constraints unless the answer says otherwise (the rest are soft unless
# the answer marks them "hard": true), as in the rule planner.
HARD_BY_DEFAULT = frozenset({"on"})

ANSWER_SCHEMA: dict[str, Any] = {
    "type": "object",
    "required": ["objects"],
    "properties": {
        "objects": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["index"],
                "properties": {
                    "index": {"type": "integer", "minimum": 0},
                    "relations": {
                        "type": "array",
                        "items": {
                            "type": "object",
                            "required": ["relation"],
                            "properties": {
                                "relation": {"type": "string", "enum": sorted(RELATIONS)},
                                "target": {"type": "integer"},
                                "value": {"type": "array", "items": {"type": "number"}},
                                "hard": {"type": "boolean"},
                            },
                        },
                    },
                },
            },
        }
    },
}


def split_batch_answer(data: Any, groups: list[str] | tuple[str, ...]) -> tuple[dict[str, Any], list[str]]:
    """The answer of each group of a batch answer, by group name, and the problems of its shape.

    A batch answer is ``{"groups": [{"group": "on:7", "objects": [...]}, ...]}`` (a list of such
    entries, or ``{"groups": {"on:7": {"objects": [...]}}}``, are read too). A group answered twice
    keeps its first answer; groups not asked for are reported; groups not answered are simply
    absent from the result (the caller reports them)."""
    if isinstance(data, dict) and isinstance(data.get("groups"), dict):
        items: Any = [{"group": k, **(v if isinstance(v, dict) else {"objects": v})} for k, v in data["groups"].items()]
    elif isinstance(data, dict) and isinstance(data.get("groups"), list):
        items = data["groups"]
    elif isinstance(data, list):
        items = data
    else:
        return {}, ['the answer must be a JSON object {"groups": [{"group": <name>, "objects": [...]}, ...]}']
    asked = set(groups)
    found: dict[str, Any] = {}
    problems: list[str] = []
    for k, item in enumerate(items):
        if not isinstance(item, dict) or not isinstance(item.get("group"), str):
            problems.append(f'entry {k} of "groups": expected {{"group": <name>, "objects": [...]}}')
            continue
        g = item["group"]
        if g not in asked:
            problems.append(f"group {g[:40]!r} was not asked for; answer only: {', '.join(groups)}")
        elif g in found:
            problems.append(f"group {g} is answered more than once; answer each group once")
        else:
            found[g] = item
    return found, problems


@dataclass(frozen=True)
class CheckedAnswer:
    """The usable part of an answer and every problem found (phrased for the model).

    ``order`` holds the objects that could be used, in answer order, with relation targets
    already converted to plan positions; offending relations and items are left out.
    ``usable`` is False when the answer's overall shape is wrong (no ``objects`` list).
    """

    order: tuple[PlannedObject, ...]
    problems: tuple[str, ...]
    missing: tuple[int, ...]
    usable: bool


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


COMPACT_RELATION = '"name", ["name", target] or ["height", min, max]'
COMPACT_ENTRY = f"[<index>, <relation>, ...] with a relation written {COMPACT_RELATION}"


def expand_compact_entry(item: list, k: int) -> tuple[dict | None, list[str]]:
    """A compact answer entry ``[index, relation, ...]`` as ``{"index", "relations"}`` and the
    problems of the relations it could not read (left out, as :func:`check_answer` leaves out bad
    relations of a full entry); ``(None, [problem])`` without a readable index. Relation names and
    targets are judged by :func:`check_answer`, for both forms alike."""
    if not item or not _is_int(item[0]):
        return None, [f"entry {k}: expected {COMPACT_ENTRY}"]
    idx, rels, problems = item[0], [], []
    for r in item[1:]:
        if isinstance(r, str):
            rels.append({"relation": r})
            continue
        if not isinstance(r, list) or not r or not isinstance(r[0], str):
            problems.append(f"object {idx}: a relation must be {COMPACT_RELATION}, got {json.dumps(r)[:80]}")
            continue
        name, args = r[0], list(r[1:])
        rel: dict[str, Any] = {"relation": name}
        if args and (isinstance(args[-1], bool) or args[-1] in ("hard", "soft")):  # "hard", or true
            flag = args.pop()
            rel["hard"] = flag if isinstance(flag, bool) else flag == "hard"
        spec = RELATIONS.get(name)
        if spec is not None and spec.values:
            rel["value"] = args
        elif len(args) == 1:
            rel["target"] = args[0]
        elif args:
            problems.append(f"object {idx}: relation {name!r} takes one target, got {json.dumps(args)[:60]}")
            continue
        rels.append(rel)
    return {"index": idx, "relations": rels}, problems


def check_answer(data: Any, request: PlanRequest) -> CheckedAnswer:
    """Validate a decoded answer against the request; see the module docstring for the format."""
    n = len(request.objects)
    if isinstance(data, dict) and isinstance(data.get("objects"), list):
        items = data["objects"]
    elif isinstance(data, list):
        items = data
    else:
        return CheckedAnswer((), ('the answer must be a JSON object {"objects": [...]}',), tuple(range(n)), False)
    kind = group_kind(request.group)
    placed_ids = {p.id for p in request.placed} | ({request.support.id} if request.support else set())
    problems: list[str] = []
    pos_of: dict[int, int] = {}  # object index -> position in the checked order
    order: list[PlannedObject] = []
    for k, item in enumerate(items):
        if isinstance(item, list):
            item, unread = expand_compact_entry(item, k)
            problems.extend(unread)
            if item is None:
                continue
        if not isinstance(item, dict) or not _is_int(item.get("index")):
            problems.append(f"entry {k}: expected {{\"index\": <integer>, \"relations\": [...]}} or {COMPACT_ENTRY}")
            continue
        idx = item["index"]
        if not 0 <= idx < n:
            problems.append(f"entry {k}: object index {idx} does not exist (valid: 0 to {n - 1})")
            continue
        if idx in pos_of:
            problems.append(f"object {idx} is listed more than once; list each object exactly once")
            continue
        rels_in = item.get("relations", [])
        if not isinstance(rels_in, list):
            problems.append(f"object {idx}: 'relations' must be a list")
            rels_in = []
        rels: list[Relation] = []
        for r in rels_in:
            rel, problem = _check_relation(r, idx, kind, pos_of, placed_ids, request)
            if problem:
                problems.append(problem)
            if rel is not None:
                rels.append(rel)
        pos_of[idx] = len(order)
        order.append(PlannedObject(idx, tuple(rels)))
    missing = tuple(i for i in range(n) if i not in pos_of)
    if missing:
        problems.append(f"objects never listed: {list(missing)}; list every object exactly once")
    return CheckedAnswer(tuple(order), tuple(problems), missing, True)


def _check_relation(r: Any, idx: int, kind: str, pos_of: dict[int, int], placed_ids: set[int],
                    request: PlanRequest) -> tuple[Relation | None, str | None]:
    if not isinstance(r, dict) or not isinstance(r.get("relation"), str):
        return None, f"object {idx}: each relation must be {{\"relation\": <name>, ...}}, got {json.dumps(r)[:80]}"
    name = r["relation"]
    spec = RELATIONS.get(name)
    if spec is None:
        allowed = ", ".join(k for k, s in RELATIONS.items() if kind in s.groups)
        return None, f"object {idx}: unknown relation {name!r}; use only: {allowed}"
    if kind not in spec.groups:
        return None, f"object {idx}: relation {name!r} is not allowed for {kind} objects"
    hard = r.get("hard", name in HARD_BY_DEFAULT)
    if not isinstance(hard, bool):
        return None, f"object {idx}: 'hard' of relation {name!r} must be true or false"
    target: int | None = None
    if spec.needs_target:
        t = r.get("target")
        if not _is_int(t):
            return None, f"object {idx}: relation {name!r} needs an integer 'target'"
        if name in CROSS_GROUP:
            allowed = _cross_targets(name, request) & placed_ids
            if t not in allowed:
                ids = sorted(allowed)
                what = "the support's id" if name == "on" else "the id of a placed floor object"
                listing = ", ".join(map(str, ids[:20])) + (", ..." if len(ids) > 20 else "") if ids else "none"
                return None, f"object {idx}: {name!r} target {t} is not {what} (valid: {listing})"
            target = t
        elif t == idx:
            return None, f"object {idx}: relation {name!r} refers to the object itself"
        elif t in pos_of:
            target = pos_of[t]
        elif 0 <= t < len(request.objects):
            return None, (f"object {idx}: {name!r} target {t} is listed later; an object may refer only to "
                          "objects listed before it")
        else:
            return None, f"object {idx}: {name!r} target {t} is not one of the objects"
    value: tuple[float, ...] = ()
    if spec.values:
        v = r.get("value")
        if (not isinstance(v, list) or len(v) != spec.values
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in v)):
            return None, f"object {idx}: relation {name!r} needs 'value': a list of {spec.values} numbers"
        value = tuple(float(x) for x in v)
        if name == "height":
            if not 0.0 <= value[0] <= value[1] <= request.room.height:
                return None, (f"object {idx}: height range {list(value)} must satisfy 0 <= min <= max <= "
                              f"{request.room.height:.2f} (the wall height)")
            tall = float(request.objects[idx].size[2])
            if value[0] + tall > request.room.height:
                return None, (f"object {idx} is {tall:.2f} m tall: its bottom edge must be at most "
                              f"{request.room.height - tall:.2f} m above the floor, not {value[0]:g} m")
    return Relation(name, target, value, hard), None


def _cross_targets(name: str, request: PlanRequest) -> set[int]:
    """Instance ids an ``on`` (the support) or ``above`` (placed floor objects) relation may name."""
    if name == "on":
        return {request.support.id} if request.support is not None else {p.id for p in request.placed}
    return {p.id for p in request.placed if p.group == "floor"}
