"""Prompt templates: editable data files rendered into chat messages.

Templates live in ``assist3d/resources/prompts/`` (``floor.txt``, ``wall.txt``, ``on_top.txt``,
``on_top_batch.txt``, ``vlm_score.txt``, ``repair.txt``, ``room_objects.txt``); ``llm.prompt_dir`` may name a
folder whose files override the
built-in ones file by file. A template holds a ``### system`` and a ``### user`` section (lines
before the first section marker are comments for the editor) and ``$name`` template fields filled
with :class:`string.Template` (write ``$$`` for a literal dollar sign):

``$group`` the group name, ``$relations`` the relation vocabulary allowed in the group,
``$objects`` the numbered object list with names and sizes, ``$count`` the number of objects,
``$room`` the room description, ``$placed`` the already-placed instances the group may refer to,
``$support`` the supporting instance (on-top groups); ``repair.txt`` gets ``$problems``;
``on_top_batch.txt`` (several on-top groups in one prompt, ``llm.on_top_batch``) gets ``$room``,
``$relations``, ``$count`` (the number of groups) and ``$groups`` (one block per group: its name,
support and numbered objects).
"""

from __future__ import annotations

import string
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from ..core.contracts import PlacedInstance, Room
from ..core.errors import ConfigError
from ..planning.relations import CROSS_GROUP, RELATIONS, PlanRequest, group_kind

TEMPLATE_FILES = {"floor": "floor.txt", "wall": "wall.txt", "on": "on_top.txt", "on_batch": "on_top_batch.txt",
                  "floor_compact": "floor_compact.txt", "wall_compact": "wall_compact.txt",
                  "on_compact": "on_top_compact.txt", "on_batch_compact": "on_top_batch_compact.txt",
                  "vlm": "vlm_score.txt", "repair": "repair.txt", "room": "room_objects.txt"}
_NAME_MAX = 60


@dataclass(frozen=True)
class Template:
    """A parsed template: where it came from and its two sections."""

    source: str
    system: str
    user: str

    def render(self, values: dict[str, str]) -> tuple[str, str]:
        try:
            return (string.Template(self.system).substitute(values).strip(),
                    string.Template(self.user).substitute(values).strip())
        except KeyError as e:
            raise ConfigError(f"{self.source}: unknown template field ${e.args[0]}; known: "
                              f"{', '.join('$' + k for k in sorted(values))} (write $$ for a dollar sign)") from None
        except ValueError as e:
            raise ConfigError(f"{self.source}: bad template field ({e}); write $$ for a dollar sign") from None


def parse_template(text: str, source: str) -> Template:
    sections: dict[str, list[str]] = {}
    current: str | None = None
    for line in text.splitlines():
        stripped = line.strip().lower()
        if stripped in ("### system", "### user"):
            current = stripped[4:]
            if current in sections:
                raise ConfigError(f"{source}: section '### {current}' appears twice")
            sections[current] = []
        elif current is not None:
            sections[current].append(line)
    if "user" not in sections:
        raise ConfigError(f"{source}: no '### user' section (a template needs '### system' and '### user' lines)")
    return Template(source, "\n".join(sections.get("system", [])), "\n".join(sections["user"]))


def load_template(name: str, prompt_dir: str | Path | None = None) -> Template:
    """The template ``name`` (a key of TEMPLATE_FILES), from ``prompt_dir`` when it has the file."""
    if name not in TEMPLATE_FILES:
        raise ConfigError(f"unknown prompt template {name!r}; known: {', '.join(TEMPLATE_FILES)}")
    fname = TEMPLATE_FILES[name]
    if prompt_dir:
        p = Path(prompt_dir).expanduser() / fname
        if p.is_file():
            try:
                return parse_template(p.read_text(encoding="utf-8"), str(p))
            except (OSError, UnicodeDecodeError) as e:
                raise ConfigError(f"{p}: cannot read the prompt template ({e})") from None
        if not Path(prompt_dir).expanduser().is_dir():
            raise ConfigError(f"llm.prompt_dir {prompt_dir}: not a folder")
    res = resources.files("assist3d") / "resources" / "prompts" / fname
    return parse_template(res.read_text(encoding="utf-8"), f"assist3d/resources/prompts/{fname}")


# ---------------------------------------------------------------------------------------------
# Describing a request in words
# ---------------------------------------------------------------------------------------------


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


def describe_room(room: Room) -> str:
    pts = np.asarray(room.polygon, dtype=np.float64)
    x, y = pts[:, 0], pts[:, 1]
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    ext = pts.max(0) - pts.min(0)
    shape = "rectangular" if len(pts) == 4 else f"{len(pts)}-sided"
    doors = sum(1 for o in room.openings if o.kind == "door")
    windows = sum(1 for o in room.openings if o.kind == "window")
    return (f"{shape} room, {ext[0]:.1f} x {ext[1]:.1f} m overall, floor area {area:.1f} m^2, "
            f"wall height {room.height:.2f} m, {doors} door(s), {windows} window(s)")


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


def render_repair_message(problems: list[str] | tuple[str, ...], prompt_dir: str | Path | None = None,
                          max_lines: int = 40) -> str:
    lines = [f"- {p}" for p in problems[:max_lines]]
    if len(problems) > max_lines:
        lines.append(f"- ... and {len(problems) - max_lines} more")
    _, user = load_template("repair", prompt_dir).render({"problems": "\n".join(lines)})
    return user
