"""docs/llm.md's "full `llm:` section with the defaults" names every LLMConfig field with its real default,
so a new setting cannot be left out of the reference, nor a changed default go stale there."""

from __future__ import annotations

import re
from pathlib import Path

import yaml

from assist3d.config import LLMConfig

DOC = Path(__file__).resolve().parents[2] / "docs" / "llm.md"
EXAMPLES = {"base_url", "model"}  # shown with example values; their default (None) is said in the comment


def _documented() -> dict:
    text = DOC.read_text(encoding="utf-8")
    m = re.search(r"A full `llm:` section with the defaults.*?```yaml\n(.*?)```", text, re.DOTALL)
    assert m, "docs/llm.md lost its full llm: section"
    return yaml.safe_load(m.group(1))["llm"]


def test_the_llm_reference_lists_every_field_with_its_default():
    documented = _documented()
    fields = LLMConfig.model_fields
    assert set(documented) == set(fields), (f"missing: {sorted(set(fields) - set(documented))}; "
                                            f"unknown: {sorted(set(documented) - set(fields))}")
    stale = {k: (v, fields[k].default) for k, v in documented.items()
             if k not in EXAMPLES and v != fields[k].default}
    assert not stale, f"documented default != LLMConfig default: {stale}"
