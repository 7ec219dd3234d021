"""Holodeck's object plan from an LLM: the objects of one room type, for ``selection.strategy:
room-type`` when an endpoint is configured.

The model gets the room type, the room and the catalog's class names per group (canonical names,
see :mod:`assist3d.core.taxonomy.classes`), and answers with floor and wall entries (class, quantity,
whether the copies are one model) and the classes of the small objects
(``resources/prompts/room_objects.txt``). :func:`check_room_answer` turns the answer into a
:class:`~assist3d.core.taxonomy.roomtypes.RoomTemplate` with every entry certain (probability 1):
unknown class names are dropped with a reason (never mapped to a close name, as for relations),
quantities are clamped to 1..8. No repair round: an unusable answer, or a failed call, leaves the
built-in template of the room type in charge, with the reason in the layout's notes.
"""

from __future__ import annotations

from typing import Any

from ..core.contracts import Room
from ..core.taxonomy.classes import normalise_class
from ..core.taxonomy.roomtypes import ROOM_TEMPLATES, Item, RoomTemplate
from ..llm.prompts import describe_room, load_template

MAX_QUANTITY = 8
MAX_ENTRIES = {"floor": 20, "wall": 10, "small": 12}
# classes that never carry small objects (seats, beds, fixtures, wall decoration): the templates' choice
NO_HOLD = frozenset(i.cls for t in ROOM_TEMPLATES.values() for i in t.floor + t.wall if not i.holds)
_VOCAB_MAX = 600  # class names listed per group (a prompt, not a catalog dump)


def room_messages(room_type: str, room: Room, vocab: dict[str, tuple[str, ...]],
                  prompt_dir: str | None = None) -> list[dict[str, str]]:
    """System and user messages asking for the objects of a ``room_type``; ``vocab`` maps
    "floor", "wall" and "obj" to the class names the model may use."""
    def listing(names: tuple[str, ...]) -> str:
        names = tuple(names)[:_VOCAB_MAX]
        return ", ".join(names) if names else "(none)"

    values = {"room_type": room_type, "room": describe_room(room), "floor_classes": listing(vocab.get("floor", ())),
              "wall_classes": listing(vocab.get("wall", ())), "small_classes": listing(vocab.get("obj", ()))}
    system, user = load_template("room", prompt_dir).render(values)
    messages = [{"role": "system", "content": system}] if system else []
    return messages + [{"role": "user", "content": user}]


def _entries(data: Any, group: str, known: set[str], problems: list[str]) -> tuple[Item, ...]:
    if data is None:
        return ()
    if not isinstance(data, list):
        problems.append(f'"{group}" is not a list')
        return ()
    items: list[Item] = []
    for k, e in enumerate(data):
        if len(items) == MAX_ENTRIES[group]:
            problems.append(f"{group}: entries after the first {MAX_ENTRIES[group]} ignored")
            break
        if not isinstance(e, dict) or not isinstance(e.get("class"), str):
            problems.append(f'{group} entry {k}: not an object with a "class" name')
            continue
        cls = normalise_class(e["class"])
        if cls not in known:
            problems.append(f"{group} entry {k}: unknown class {e['class']!r} (not in the list); dropped")
            continue
        q = e.get("quantity", 1)
        if isinstance(q, bool) or not isinstance(q, (int, float)) or q != q:
            problems.append(f"{group} entry {k} ({cls}): quantity {q!r} is not a number; 1 used")
            q = 1
        n = int(min(max(round(q), 1), MAX_QUANTITY))
        if n != q:
            problems.append(f"{group} entry {k} ({cls}): quantity {q!r} clamped to {n}")
        same = e.get("same", True)
        items.append(Item(cls, 1.0, (n, n), same=bool(same) if isinstance(same, bool) else True,
                          holds=cls not in NO_HOLD))
    return tuple(items)


def check_room_answer(data: Any, room_type: str,
                      vocab: dict[str, tuple[str, ...]]) -> tuple[RoomTemplate | None, list[str]]:
    """The template an answer describes (None when it has no usable floor entry) and its problems.

    Small-object classes the answer leaves out (or names wrongly) fall back to the built-in
    template's for ``room_type``."""
    problems: list[str] = []
    if not isinstance(data, dict):
        return None, ["the answer is not a JSON object"]
    known = {g: {normalise_class(c) for c in vocab.get(g, ())} for g in ("floor", "wall", "obj")}
    floor = _entries(data.get("floor"), "floor", known["floor"], problems)
    wall = _entries(data.get("wall"), "wall", known["wall"], problems)
    small: list[str] = []
    raw_small = data.get("small") or []
    if not isinstance(raw_small, list):
        problems.append('"small" is not a list')
        raw_small = []
    for k, name in enumerate(raw_small):
        if len(small) == MAX_ENTRIES["small"]:
            problems.append(f"small: classes after the first {MAX_ENTRIES['small']} ignored")
            break
        cls = normalise_class(name) if isinstance(name, str) else None
        if cls is None or cls not in known["obj"]:
            problems.append(f"small entry {k}: unknown class {name!r} (not in the list); dropped")
        elif cls not in small:
            small.append(cls)
    if not floor:
        return None, problems + ["no usable floor object"]
    if not small:
        problems.append(f"no usable small-object class; the {room_type} template's are used")
        small = list(ROOM_TEMPLATES[room_type].small)
    return RoomTemplate(floor, wall, tuple(small)), problems
