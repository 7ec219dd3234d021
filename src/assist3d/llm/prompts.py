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

This module holds what every prompt needs (templates, the room description, the repair message);
the relation planner's prompts (the fields above that describe a planning request) are rendered by
:mod:`assist3d.planning.llm_prompts`, so ``llm`` never imports ``planning``.
"""

from __future__ import annotations

import string
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from ..core.contracts import Room
from ..core import reading
from ..core.errors import ConfigError

TEMPLATE_FILES = {"floor": "floor.txt", "wall": "wall.txt", "on": "on_top.txt", "on_batch": "on_top_batch.txt",
                  "floor_compact": "floor_compact.txt", "wall_compact": "wall_compact.txt",
                  "on_compact": "on_top_compact.txt", "on_batch_compact": "on_top_batch_compact.txt",
                  "vlm": "vlm_score.txt", "repair": "repair.txt", "room": "room_objects.txt"}


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
            return parse_template(reading.read_text(p, error=ConfigError, what="prompt template"), str(p))
        if not Path(prompt_dir).expanduser().is_dir():
            raise ConfigError(f"llm.prompt_dir {prompt_dir}: not a folder")
    res = resources.files("assist3d") / "resources" / "prompts" / fname
    return parse_template(res.read_text(encoding="utf-8"), f"assist3d/resources/prompts/{fname}")


# ---------------------------------------------------------------------------------------------
# Describing the room in words; the repair message
# ---------------------------------------------------------------------------------------------


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


def render_repair_message(problems: list[str] | tuple[str, ...], prompt_dir: str | Path | None = None,
                          max_lines: int = 40) -> str:
    lines = [f"- {p}" for p in problems[:max_lines]]
    if len(problems) > max_lines:
        lines.append(f"- ... and {len(problems) - max_lines} more")
    _, user = load_template("repair", prompt_dir).render({"problems": "\n".join(lines)})
    return user
