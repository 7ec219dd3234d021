"""The LLM relation planner: one chat completion per group, one repair round, rules as fallback.

``LLMPlanner(cfg.llm, fallback=RulePlanner(...)).plan(request, rng=rng)`` returns a
:class:`~assist3d.planning.relations.GroupPlan` that always passes ``validate_plan``:

1. The group's prompt template is rendered (vocabulary, numbered objects with sizes, room,
   placed instances, worked example) and sent; the answer is decoded with ``json.loads`` and
   checked by :func:`assist3d.planning.llm_schema.check_answer`.
2. Every problem (invalid JSON, unknown relation names, unknown or later targets, duplicated or
   missing objects, bad values) is sent back in ONE repair round.
3. What is still wrong after the repair is dropped, each with a reason in ``GroupPlan.notes``
   (and the log); objects the model never listed are appended in the fallback planner's order
   with the fallback planner's relations.
4. On any failure (HTTP error after retries, time-out, oversized answer, nothing usable after
   the repair) the fallback planner plans the group and ``GroupPlan.planner`` is its name
   ("rules"); otherwise it is ``"llm:<model>"``.

``GroupPlan.stats``: llm_calls, cache_hits, repairs, prompt_tokens, completion_tokens, seconds
(``llm_seconds`` holds the same number under the layout summary's name).

``plan_batch`` asks for several on-top groups of a scene in one prompt (``llm.on_top_batch``):
each group's part of the answer goes through steps 2-4 on its own (one repair round for the whole
batch, listing every group's problems), so one bad group falls back to the rules without taking
the others with it.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np

from ..config import LLMConfig
from ..core.contracts import Relation, Room
from ..core.errors import ConfigError, LLMError, inert
from ..core.taxonomy.roomtypes import RoomTemplate
from ..llm.cache import ResponseCache
from ..llm.client import ChatAnswer, ChatClient, Usage
from ..llm.prompts import render_repair_message
from .llm_rooms import check_room_answer, room_messages
from ..llm.schema import parse_json_text, salvage_groups, salvage_objects
from .llm_prompts import render_batch_messages, render_plan_messages
from .llm_schema import CheckedAnswer, check_answer, split_batch_answer
from .relations import CROSS_GROUP, GroupPlan, PlannedObject, Planner, PlanRequest, validate_plan

log = logging.getLogger(__name__)

CUT_OFF = "the answer was cut off at the token limit; answer more briefly (at most 2 relations per object)"


class LLMPlanner:
    """Plans groups with an OpenAI-compatible chat model; ``fallback`` plans what it cannot."""

    def __init__(self, cfg: LLMConfig, fallback: Planner, *, client: ChatClient | None = None,
                 cache: ResponseCache | None = None) -> None:
        if not cfg.base_url or not cfg.model:
            raise ConfigError("the LLM planner needs llm.base_url and llm.model "
                              "(--llm-base-url / --llm-model or the config file)")
        self.cfg = cfg
        self.fallback = fallback
        self.client = client if client is not None else ChatClient(cfg, cache=cache)
        self.name = f"llm:{cfg.model}"

    # ------------------------------------------------------------------------------------------
    def plan(self, request: PlanRequest, *, rng: np.random.Generator) -> GroupPlan:
        usage = Usage()
        t0 = time.monotonic()
        repairs = 0
        extra_notes: list[str] = []
        if not request.objects:
            return self._with_stats(self.fallback.plan(request, rng=rng), usage, repairs, (), t0)
        try:
            messages = render_plan_messages(request, self.cfg.prompt_dir, self.cfg.answer_format)
            first = self.client.complete(messages, usage=usage)
            checked, problems = _check(first, request)
            if problems:
                repairs = 1
                try:
                    second = self._repair(request.group, messages, first, problems, usage)
                    checked2, problems2 = _check(second, request)
                except LLMError as e:
                    if checked is None:
                        raise
                    checked2, problems2 = None, [f"the repair request failed ({e})"]
                if checked2 is not None:
                    checked, problems = checked2, problems2
                elif checked is not None:
                    kept = f"repair answer unusable ({'; '.join(problems2[:2])}); kept the first answer"
                    log.warning("%s %s: %s", self.name, request.group, inert(kept))
                    extra_notes.append(kept)
            plan, notes = self._finish(request, checked, problems, extra_notes, rng)  # raises when nothing is usable
        except LLMError as e:
            return self._fell_back(request, e, rng, usage, repairs, t0)
        return self._with_stats(plan, usage, repairs, notes, t0)

    def plan_batch(self, requests: list[PlanRequest] | tuple[PlanRequest, ...], *,
                   rngs: list[np.random.Generator]) -> list[GroupPlan]:
        """The plans of several on-top groups of one scene from one chat completion, in
        ``requests`` order; ``rngs[i]`` is group i's stream (used only where the fallback planner
        plans). Each group's answer is checked on its own; every group's problems go back in one
        repair round, and a group that had none keeps its first answer. A group without a usable
        answer after the repair is planned by the fallback planner, with the reason in its notes;
        when the request itself fails, every group is. The batch's counters (calls, cache hits,
        repairs, tokens, seconds) are on the first plan's stats and zero on the others, so sums
        over a layout's groups stay right."""
        requests = list(requests)
        if len(requests) != len(rngs):
            raise ValueError("plan_batch needs one random stream per request")
        if len(requests) == 1:
            return [self.plan(requests[0], rng=rngs[0])]
        usage = Usage()
        t0 = time.monotonic()
        repairs = 0
        extra_notes: list[list[str]] = [[] for _ in requests]
        try:
            messages = render_batch_messages(requests, self.cfg.prompt_dir, self.cfg.answer_format)
            first = self.client.complete(messages, usage=usage)
            results, general = _check_batch(first, requests)
            if any(problems for _, problems in results):  # a problem of the whole answer alone costs no repair
                repairs = 1
                listed = general + [f"group {r.group}: {p}" for r, (_, ps) in zip(requests, results) for p in ps]
                try:
                    second = self._repair(f"batch of {len(requests)} groups", messages, first, listed, usage)
                    results2, _ = _check_batch(second, requests)
                except LLMError as e:
                    if all(checked is None for checked, _ in results):
                        raise
                    results2 = [(None, [f"the repair request failed ({e})"]) for _ in requests]
                for i, ((c1, p1), (c2, p2)) in enumerate(zip(results, results2)):
                    if not p1:
                        continue  # nothing wrong with this group's first answer
                    if c2 is not None:
                        results[i] = (c2, p2)
                    elif c1 is not None:
                        kept = f"repair answer unusable ({'; '.join(p2[:2])}); kept the first answer"
                        log.warning("%s %s: %s", self.name, requests[i].group, inert(kept))
                        extra_notes[i].append(kept)
                    else:
                        results[i] = (None, p2 or p1)
        except LLMError as e:
            return [self._fell_back(r, e, g, usage if i == 0 else Usage(), repairs if i == 0 else 0, t0)
                    for i, (r, g) in enumerate(zip(requests, rngs))]
        plans = []
        for i, (request, rng, (checked, problems)) in enumerate(zip(requests, rngs, results)):
            mine, mine_repairs = (usage, repairs) if i == 0 else (Usage(), 0)
            try:
                plan, notes = self._finish(request, checked, problems, extra_notes[i], rng)
            except LLMError as e:
                plans.append(self._fell_back(request, e, rng, mine, mine_repairs, t0))
                continue
            plans.append(self._with_stats(plan, mine, mine_repairs, notes, t0))
        return plans

    def _repair(self, what: str, messages: list[dict[str, str]], first: ChatAnswer, problems: list[str],
                usage: Usage) -> ChatAnswer:
        """The one repair round: the first answer and its problems go back; the second answer."""
        log.info("%s %s: %d problem(s) in the answer; asking for a repair: %s", self.name, what, len(problems),
                 inert("; ".join(problems[:5])))
        return self.client.complete(messages + [
            {"role": "assistant", "content": first.content},
            {"role": "user", "content": render_repair_message(problems, self.cfg.prompt_dir)},
        ], usage=usage)

    def _finish(self, request: PlanRequest, checked: CheckedAnswer | None, problems: list[str],
                extra_notes: list[str], rng: np.random.Generator) -> tuple[GroupPlan, tuple[str, ...]]:
        """The group's plan and notes from its checked answer (missing objects appended in the
        fallback planner's order); raises LLMError when the answer has nothing usable."""
        if checked is None:
            raise LLMError(f"no usable answer after one repair round ({'; '.join(problems[:3])})")
        if not checked.order:
            raise LLMError("the answer lists none of the objects")
        notes = extra_notes + [f"dropped: {p}" for p in problems if not p.startswith("objects never listed")]
        for n in notes:
            log.info("%s %s: %s", self.name, request.group, inert(n))
        order = list(checked.order)
        if checked.missing:
            order, extra = _append_missing(order, checked.missing, request, self.fallback, rng)
            notes.extend(extra)
        plan = GroupPlan(request.group, tuple(order), self.name, tuple(notes))
        bad = validate_plan(plan, request)
        if bad:  # cannot happen with a checked answer; keep the guarantee anyway
            reason = f"LLM plan for group {request.group} failed validation ({'; '.join(bad[:3])}); rules took over"
            log.error("%s", inert(reason))
            fb = self.fallback.plan(request, rng=rng)
            return fb, (reason, *fb.notes)
        return plan, plan.notes

    def _fell_back(self, request: PlanRequest, error: LLMError, rng: np.random.Generator, usage: Usage,
                   repairs: int, t0: float) -> GroupPlan:
        reason = f"LLM failed for group {request.group}: {error}; the rule planner took over"
        log.warning("%s", inert(reason))
        plan = self.fallback.plan(request, rng=rng)
        return self._with_stats(plan, usage, repairs, (reason, *plan.notes), t0)

    def propose_room(self, room_type: str, room: Room,
                     vocab: dict[str, tuple[str, ...]]) -> tuple[RoomTemplate | None, dict]:
        """The objects of a ``room_type`` as the model chooses them (Holodeck's object plan):
        ``(RoomTemplate or None, stats)``; None (the built-in template is then used) when the call
        fails or the answer has no usable floor object, with the reason in ``stats["notes"]``."""
        usage = Usage()
        t0 = time.monotonic()
        notes: list[str] = []
        template: RoomTemplate | None = None
        try:
            answer = self.client.complete(room_messages(room_type, room, vocab, self.cfg.prompt_dir), usage=usage)
            data, err = parse_json_text(answer.content)
            if err is not None:
                raise LLMError(err)
            template, problems = check_room_answer(data, room_type, vocab)
            notes += [f"room objects: {p}" for p in problems]
            if template is None:
                raise LLMError("; ".join(problems[-3:]))
        except LLMError as e:
            notes.append(f"LLM room objects failed for a {room_type} ({e}); the built-in template was used")
            log.warning("%s: %s", self.name, inert(notes[-1]))
        stats: dict[str, Any] = usage.as_dict()
        stats["llm_seconds"] = round(usage.seconds, 4)
        stats["seconds"] = round(time.monotonic() - t0, 4)
        stats["notes"] = notes
        return template, stats

    def _with_stats(self, plan: GroupPlan, usage: Usage, repairs: int, notes: tuple[str, ...],
                    t0: float) -> GroupPlan:
        stats: dict[str, Any] = dict(plan.stats)
        stats.update(usage.as_dict())
        stats["repairs"] = repairs
        stats["seconds"] = round(time.monotonic() - t0, 4)
        stats["llm_seconds"] = round(usage.seconds, 4)
        return GroupPlan(plan.group, plan.order, plan.planner, tuple(notes), stats)


def _check(answer: ChatAnswer, request: PlanRequest) -> tuple[CheckedAnswer | None, list[str]]:
    """The usable part of an answer (None if nothing is) and its problems, phrased for the model."""
    cut = [CUT_OFF] if answer.finish_reason == "length" else []
    data, err = parse_json_text(answer.content)
    if err is not None:
        items = salvage_objects(answer.content)
        if not items:
            return None, [*cut, err]
        checked = check_answer({"objects": items}, request)
        return checked, [*cut, f"{err}; only the first {len(items)} complete entries could be read",
                         *checked.problems]
    checked = check_answer(data, request)
    if not checked.usable:
        return None, [*cut, *checked.problems]
    return checked, [*cut, *checked.problems]


def _check_batch(answer: ChatAnswer, requests: list[PlanRequest]
                 ) -> tuple[list[tuple[CheckedAnswer | None, list[str]]], list[str]]:
    """Each group's usable part and problems in a batch answer (in ``requests`` order), and the
    problems of the answer as a whole."""
    general = [CUT_OFF] if answer.finish_reason == "length" else []
    names = [r.group for r in requests]
    data, err = parse_json_text(answer.content)
    if err is not None:
        entries = salvage_groups(answer.content)
        general.append(err if not entries else f"{err}; only the first {len(entries)} complete groups could be read")
        data = {"groups": entries}
    found, shape = split_batch_answer(data, names)
    general.extend(shape)
    results: list[tuple[CheckedAnswer | None, list[str]]] = []
    for request in requests:
        item = found.get(request.group)
        if item is None:
            results.append((None, [f"group {request.group} is missing from the answer; answer every group"]))
            continue
        checked = check_answer(item, request)
        results.append((checked if checked.usable else None, list(checked.problems)))
    return results, general


def _append_missing(order: list[PlannedObject], missing: tuple[int, ...], request: PlanRequest,
                    fallback: Planner, rng: np.random.Generator) -> tuple[list[PlannedObject], list[str]]:
    """Append ``missing`` objects in the fallback plan's order with its relations, re-targeted
    to positions in the merged order (relations to objects not yet in it are dropped)."""
    notes: list[str] = []
    fb = fallback.plan(request, rng=rng)
    fb_source = [p.source for p in fb.order]
    pos_of = {p.source: i for i, p in enumerate(order)}
    want = set(missing)
    ordered = [s for s in fb_source if s in want] + sorted(want - set(fb_source))
    for s in ordered:
        item = next((p for p in fb.order if p.source == s), None)
        rels: list[Relation] = []
        for r in item.relations if item is not None else ():
            if r.kind in CROSS_GROUP or r.target is None:
                rels.append(r)
                continue
            src = fb_source[r.target] if 0 <= r.target < len(fb_source) else None
            if src is not None and src in pos_of:
                rels.append(Relation(r.kind, pos_of[src], r.value, r.hard))
        pos_of[s] = len(order)
        order.append(PlannedObject(s, tuple(rels)))
    notes.append(f"objects {sorted(want)} missing from the answer; appended with {fb.planner} relations")
    return order, notes
