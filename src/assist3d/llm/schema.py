"""JSON answers from a model: decoding and salvaging, nothing evaluated.

:func:`parse_json_text` decodes an answer with ``json.loads`` only (a Markdown code fence around it,
or prose before the object, is tolerated); :func:`salvage_objects` / :func:`salvage_groups` read the
complete entries at the start of the ``"objects"`` / ``"groups"`` list of an answer cut off at the
token limit (``raw_decode`` only).

The relation planner's answer format and its validation are :mod:`assist3d.planning.llm_schema`,
so ``llm`` never imports ``planning``.
"""

from __future__ import annotations

import json
import re
from typing import Any

_FENCE = re.compile(r"^\s*```[a-zA-Z0-9_-]*\s*\n(.*?)\n\s*```\s*$", re.DOTALL)


def parse_json_text(text: str) -> tuple[Any | None, str | None]:
    """``(value, None)`` for a JSON text (optionally inside a Markdown code fence), or
    ``(None, problem)``. Only ``json.loads`` / ``raw_decode`` are used; nothing is evaluated."""
    m = _FENCE.match(text)
    body = m.group(1) if m else text.strip()
    try:
        return json.loads(body), None
    except json.JSONDecodeError as e:
        first = body.find("{")
        if first > 0:  # prose before the object: decode the first JSON object only
            try:
                value, _ = json.JSONDecoder().raw_decode(body[first:])
                return value, None
            except json.JSONDecodeError:
                pass
        return None, f"the answer is not valid JSON ({e.msg} at line {e.lineno} column {e.colno})"


def _list_key(key: str) -> re.Pattern[str]:
    return re.compile(r'"' + re.escape(key) + r'"\s*:\s*\[')


_OBJECTS_KEY = _list_key("objects")
_GROUPS_KEY = _list_key("groups")


def _salvage_list(text: str, key: re.Pattern[str]) -> list[Any]:
    """The complete entries at the start of the list under ``key`` in a broken answer."""
    m = key.search(text)
    if m is None:
        return []
    dec = json.JSONDecoder()
    items: list[Any] = []
    pos = m.end()
    while True:
        while pos < len(text) and text[pos] in " \t\r\n,":
            pos += 1
        if pos >= len(text) or text[pos] not in "{[":  # a full entry or a compact one
            return items
        try:
            item, pos = dec.raw_decode(text, pos)
        except json.JSONDecodeError:
            return items
        items.append(item)


def salvage_objects(text: str) -> list[Any]:
    """The complete entries at the start of the ``"objects"`` list of a broken answer (typically
    one cut off at the token limit); empty when there are none. Decoded with ``raw_decode`` only."""
    return _salvage_list(text, _OBJECTS_KEY)


def salvage_groups(text: str) -> list[Any]:
    """The complete group entries at the start of the ``"groups"`` list of a broken batch answer."""
    return _salvage_list(text, _GROUPS_KEY)
