"""The relation planner's prompts: a planning request (:class:`~assist3d.planning.relations.PlanRequest`)
described in words and rendered into chat messages with the templates of :mod:`assist3d.llm.prompts`
(``floor``, ``wall``, ``on``, ``on_batch`` and their ``_compact`` forms; the template fields are listed
there).
"""

from __future__ import annotations

from pathlib import Path

from ..core.contracts import PlacedInstance
from ..core.errors import ConfigError
from ..llm.prompts import describe_room, load_template
from .relations import CROSS_GROUP, RELATIONS, PlanRequest, group_kind

_NAME_MAX = 60


def _clean(name: str) -> str:
    name = " ".join(str(name).replace('"', "'").split())
    return name if len(name) <= _NAME_MAX else name[: _NAME_MAX - 3] + "..."


def describe_relations(kind: str, answer_format: str = "full") -> str:
    """The relations a group of ``kind`` may use, one line each, written as the answer form writes them."""
    compact = answer_format == "compact"
    lines = []
    for spec in RELATIONS.values():
        if kind not in spec.groups:
            continue
        if spec.kind in CROSS_GROUP:
            arg = "<placed instance id>" if compact else '"target": <placed instance id>'
        elif spec.needs_target:
            arg = "<index of an earlier object>" if compact else '"target": <index of an earlier object>'
        elif spec.values:
            arg = "min_m, max_m" if compact else '"value": [min_m, max_m]'
        else:
            arg = ""
        if compact:
            name = f'"{spec.kind}"'
            lines.append(f"- {f'[{name}, {arg}]' if arg else name}: {spec.description}")
        else:
            lines.append(f"- {spec.kind} ({arg or 'no target'}): {spec.description}")
    return "\n".join(lines)


def describe_objects(request: PlanRequest) -> str:
    lines = []
    for i, a in enumerate(request.objects):
        w, d, h = a.size
        lines.append(f'{i}: "{_clean(a.name)}" (class: {_clean(a.class_name)}), '
                     f"{w:.2f} x {d:.2f} x {h:.2f} m (width x depth x height)")
    return "\n".join(lines)


def _describe_instance(p: PlacedInstance) -> str:
    x, y, z = (float(v) for v in p.pose[:3, 3])
    return f"id {p.id}: {_clean(p.class_name)} at x={x:.2f}, y={y:.2f} m (base {z:.2f} m above the floor)"


def request_values(request: PlanRequest, answer_format: str = "full") -> dict[str, str]:
    """The template field values of a planning request."""
    kind = group_kind(request.group)
    placed = "\n".join(_describe_instance(p) for p in request.placed) or "(none)"
    support = _describe_instance(request.support) if request.support is not None else "(none)"
    return {"group": request.group, "relations": describe_relations(kind, answer_format),
            "objects": describe_objects(request),
            "count": str(len(request.objects)), "room": describe_room(request.room), "placed": placed,
            "support": support}


def render_plan_messages(request: PlanRequest, prompt_dir: str | Path | None = None,
                         answer_format: str = "full") -> list[dict[str, str]]:
    """System and user messages asking for the relations of ``request``'s group, in the answer
    form ``answer_format`` ("full" or "compact", ``llm.answer_format``)."""
    kind = group_kind(request.group)
    system, user = load_template(_form(kind, answer_format), prompt_dir).render(request_values(request, answer_format))
    messages = [{"role": "system", "content": system}] if system else []
    return messages + [{"role": "user", "content": user}]


def describe_group_block(request: PlanRequest) -> str:
    """One on-top group of a batch prompt: its name, its support and its numbered objects."""
    support = _describe_instance(request.support) if request.support is not None else "(none)"
    return (f'Group "{request.group}", support {support}\n'
            f"Objects of {request.group} ({len(request.objects)}), numbered:\n{describe_objects(request)}")


def _form(name: str, answer_format: str) -> str:
    """The template of planning prompt ``name`` in ``answer_format`` (compact ones are ``<name>_compact``)."""
    if answer_format not in ("full", "compact"):
        raise ConfigError(f"llm.answer_format must be 'full' or 'compact', not {answer_format!r}")
    return f"{name}_compact" if answer_format == "compact" else name


def render_batch_messages(requests: list[PlanRequest] | tuple[PlanRequest, ...],
                          prompt_dir: str | Path | None = None, answer_format: str = "full") -> list[dict[str, str]]:
    """System and user messages asking for the relations of several on-top groups of one scene
    (``llm.on_top_batch``); every request must be an on-top group of the same room."""
    if not requests or any(group_kind(r.group) != "on" for r in requests):
        raise ValueError("a batch prompt holds one or more on-top groups and nothing else")
    values = {"room": describe_room(requests[0].room), "relations": describe_relations("on", answer_format),
              "count": str(len(requests)), "groups": "\n\n".join(describe_group_block(r) for r in requests)}
    system, user = load_template(_form("on_batch", answer_format), prompt_dir).render(values)
    messages = [{"role": "system", "content": system}] if system else []
    return messages + [{"role": "user", "content": user}]
